#!/usr/bin/env bash
# What a process pays before and around its work: wall time and peak resident memory of short
# aperture commands (`--version`, a 64x48 render to EXR, the same with a PNG preview, which
# loads the OpenImageIO plugin, core/io/image_codec.h) and of `import aperture` in Python. Each is
# run RUNS times; the table gives the median wall time and the median peak RSS. With BEFORE=<an
# aperture binary>, that binary runs the same commands, alternating with BIN run by run, so
# drift in the machine's speed hits both alike. Peak RSS is GNU time's %M.
#   bash bench/startup.sh   (BIN=build/apps/aperture RUNS=21 PYTHON=.venv/bin/python)
#   BEFORE=/tmp/aperture_old bash bench/startup.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/apps/aperture}
PYTHON=${PYTHON:-.venv/bin/python}
[[ -x $BIN ]] || { echo "startup: build first ($BIN missing)"; exit 2; }
[[ -x /usr/bin/time ]] || { echo "startup: needs /usr/bin/time (Debian package time)"; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "startup: $(date -u '+%Y-%m-%d %H:%M UTC'); CPU:$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2); RUNS=${RUNS:-21}"
python3 - "$BIN" "${BEFORE:-}" "${RUNS:-21}" "$out" "$PYTHON" <<'PY'
import os, statistics, subprocess, sys, time  # noqa: E401

after, before, runs, out, python = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
tiny = ["render", "--size", "64,48", "--quiet", "--out", f"{out}/x.exr"]
commands = [
    ("aperture --version", ["--version"]),
    ("render 64x48 to EXR", tiny),
    ("render 64x48 to EXR + PNG preview", tiny + ["--preview", f"{out}/x.png"]),
]

def measure(argv, env=None):
    # Peak RSS from /usr/bin/time: a child forked from this Python process would count
    # Python's own pages in its peak (the kernel carries the peak across exec).
    rss = f"{out}/rss"
    start = time.perf_counter()
    code = subprocess.call(["/usr/bin/time", "-f", "%M", "-o", rss] + argv,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    wall = time.perf_counter() - start
    if code != 0:
        sys.exit(f"startup: {' '.join(argv)} exited {code}")
    return wall, int(open(rss).read().split()[-1]) / 1024  # KiB -> MiB

sides = [("before", before), ("after", after)] if before else [("after", after)]
rows = []
for name, args in commands:
    samples = {side: [] for side, _ in sides}
    for _ in range(runs):
        for side, binary in sides:  # alternating, run by run
            samples[side].append(measure([binary] + args))
    rows.append((name, samples))
env = dict(os.environ, PYTHONPATH=os.path.abspath("build/python"))
if os.access(python, os.X_OK):
    # What the module paid at import while it linked OpenImageIO: loading the library.
    oiio = "import ctypes; ctypes.CDLL('libOpenImageIO.so.2.4')"
    for name, code in [("python: import numpy (the floor)", "import numpy"),
                       ("python: import aperture (build tree)", "import aperture"),
                       ("python: load libOpenImageIO alone", oiio)]:
        rows.append((name, {"after": [measure([python, "-c", code], env) for _ in range(runs)]}))

def cell(values):
    return f"{1000 * statistics.median(v[0] for v in values):.1f} ms | {statistics.median(v[1] for v in values):.1f} MB"

head = "| command | " + ("before wall | before peak RSS | " if before else "") + "wall | peak RSS |"
print(head)
print("|---|" + ("---:|---:|" if before else "") + "---:|---:|")
for name, samples in rows:
    cells = [cell(samples["before"]) if "before" in samples else "– | –"] if before else []
    cells.append(cell(samples["after"]))
    print(f"| {name} | " + " | ".join(cells) + " |")
PY
