#!/usr/bin/python3
"""Run one command and report its cost as JSON.

Usage: measure.py OUT.json TIMEOUT_SECONDS -- CMD [ARGS...]

Runs CMD under coreutils `timeout -k 10 TIMEOUT_SECONDS` and writes
{"wall", "cpu_user", "cpu_sys", "cpu", "maxrss_mb", "rc", "timed_out", "cmd"}
to OUT.json. CPU time and peak RSS come from getrusage(RUSAGE_CHILDREN)
after the child has been reaped: this wrapper runs exactly one child, so
ru_maxrss is the peak resident set of the measured process (or of its
largest descendant; `timeout` itself is a few hundred kB). A fresh wrapper
process per measurement keeps one run's peak from leaking into the next.
Stdout/stderr of CMD go to OUT.json with .log appended.
"""
import json
import resource
import subprocess
import sys
import time


def main():
    if len(sys.argv) < 5 or sys.argv[3] != '--':
        sys.exit(__doc__)
    out, limit, cmd = sys.argv[1], float(sys.argv[2]), sys.argv[4:]
    full = ['timeout', '-k', '10', '%g' % limit] + cmd
    with open(out + '.log', 'wb') as log:
        t0 = time.perf_counter()
        rc = subprocess.run(full, stdout=log, stderr=subprocess.STDOUT).returncode
        wall = time.perf_counter() - t0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    res = {
        'cmd': cmd,
        'rc': rc,
        'timed_out': rc in (124, 137),
        'wall': wall,
        'cpu_user': ru.ru_utime,
        'cpu_sys': ru.ru_stime,
        'cpu': ru.ru_utime + ru.ru_stime,
        'maxrss_mb': ru.ru_maxrss / 1024.0,  # Linux: kB
    }
    with open(out, 'w') as f:
        json.dump(res, f, indent=1)
        f.write('\n')


if __name__ == '__main__':
    main()
