#!/usr/bin/env python3
"""How much of each CPU this machine's host takes away, in gaps a spinning thread sees.

One process per CPU, pinned to it, reads the clock in a tight loop for SECONDS and counts the
gaps between two reads longer than GAP_US: time in which the CPU ran nothing of ours although
nothing else in this machine wanted it (run it on an idle machine). On a virtual machine whose
host deschedules its vCPUs, the gaps are the host's; /proc/stat's steal column may still read 0.
A load or a frame of a few milliseconds that meets such a gap takes that much longer, on one of
its two cores: the reason bench/RESULTS.md gives medians of alternating rounds.

    python3 bench/host_steal.py [SECONDS] [GAP_US]    (defaults: 2 s, 50 us)
"""
import multiprocessing
import os
import platform
import sys
import time


def cpu_model():
    with open('/proc/cpuinfo') as f:
        for line in f:
            if line.startswith('model name'):
                return line.split(':', 1)[1].strip()
    return platform.processor()


def probe(cpu, seconds, gap_us, out):
    os.sched_setaffinity(0, {cpu})
    clock = time.perf_counter_ns
    gap_ns = gap_us * 1000
    start = last = clock()
    end = start + int(seconds * 1e9)
    gaps, lost, longest = 0, 0, 0
    while last < end:
        now = clock()
        if now - last > gap_ns:
            gaps += 1
            lost += now - last
            longest = max(longest, now - last)
        last = now
    out.put((cpu, gaps, lost / 1e6, longest / 1e3, (last - start) / 1e6))


def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 2.0
    gap_us = float(sys.argv[2]) if len(sys.argv) > 2 else 50.0
    cpus = sorted(os.sched_getaffinity(0))
    print(f'# {cpu_model()}, {len(cpus)} CPUs, {time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}, '
          f'load average {os.getloadavg()[0]:.2f}')
    out = multiprocessing.Queue()
    procs = [multiprocessing.Process(target=probe, args=(c, seconds, gap_us, out)) for c in cpus]
    for p in procs:
        p.start()
    rows = sorted(out.get() for _ in procs)
    for p in procs:
        p.join()
    print(f'| CPU | gaps > {gap_us:g} us | time lost | longest gap |')
    print('|---:|---:|---:|---:|')
    for cpu, gaps, lost_ms, longest_us, total_ms in rows:
        print(f'| {cpu} | {gaps} | {lost_ms:.0f} ms of {total_ms:.0f} ({100 * lost_ms / total_ms:.1f} %) '
              f'| {longest_us / 1000:.1f} ms |')


if __name__ == '__main__':
    main()
