#!/usr/bin/env bash
# Side by side, interleaved: the binary before issue 10 (53a691b) and after, dragon reference view.
set -euo pipefail
BEFORE=${BEFORE:?path of the aperture binary built at 53a691b}
AFTER=${AFTER:-build/apps/aperture}
D=${D:-../shared/meshes/stanford/dragon_vrip.ply}
VIEW="--eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --fov 30 --size 1920,1080"
out=${OUT:-/tmp/b10}; mkdir -p $out
for round in 1 2 3; do
  for cfg in "dn1:--aov depth,normal --spp 1 --baseline" "dn4:--aov depth,normal --spp 4" "cd4:--aov color,depth --spp 4"; do
    name=${cfg%%:*}; flags=${cfg#*:}
    for which in before after; do
      bin=$BEFORE; [ $which = after ] && bin=$AFTER
      $bin bench --mesh $D $VIEW $flags --frames 10 --warmup 2 --builds 1 --quiet --json $out/$name-$which-$round.json >/dev/null 2>&1 || echo "fail $name $which"
    done
  done
done
python3 - "$out" <<'PY'
import json,glob,statistics,os,sys
rows=[]
for name,label in [('dn1','depth,normal, 1 spp'),('dn4','depth,normal, 4 spp'),('cd4','color,depth, 4 spp')]:
    r={}
    for which in ['before','after']:
        vals=[];base=[]
        for f in sorted(glob.glob(f'{sys.argv[1]}/{name}-{which}-*.json')):
            d=json.load(open(f)); vals.append(d['mrays_per_s_median'])
            if 'baseline_mrays_per_s_median' in d: base.append(d['baseline_mrays_per_s_median'])
        r[which]=(statistics.median(vals) if vals else float('nan'), statistics.median(base) if base else None, vals)
    rows.append((label,r))
for label,r in rows:
    b,a=r['before'],r['after']
    line=f"| {label} | {b[0]:.1f} | {a[0]:.1f} | {a[0]/b[0]:.3f} |"
    if a[1]: line+=f" {b[0]/b[1]:.3f} / {a[0]/a[1]:.3f} |"
    else: line+=" |"
    print(line, [round(x,1) for x in b[2]], [round(x,1) for x in a[2]])
PY
