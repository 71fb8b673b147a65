#!/usr/bin/env python3
"""readmefigures.py - the figures README.md shows against what its commands
printed and wrote (tests/clients/readme.sh). No expected number lives here:
the README is the expectation, the run is the truth.

usage: readmefigures.py README.md LOG DIR
  LOG  what the README's commands printed (stdout and stderr)
  DIR  where they ran (the reports they wrote are read from there)

Checked, each printing one "ok - ..." or "FAIL - ...":
  - every shown line "qdc: IN -> OUT: mean ratio ... (outcome, N iterations,
    solver, T s)" against the line the run printed for the same IN -> OUT
    (all of it but the time);
  - every shown "qdc: outcome: ..." (the outcome in words) is a line a run
    printed, word for word;
  - the 10-degree dihedral table before/after against the 1-degree
    histograms of the report it names ("from `R.json`"), summed per 10 degrees;
  - the summary lines under it (mean ratio, worst, dihedral range, tets with
    an angle < 5 and > 175 degrees) and "moved by at most P% of the
    bounding-box diagonal" against that report, at the precision shown.
Standard library only (no numpy).
"""
import json
import os
import re
import sys

NFAIL = 0


def ok(msg):
    print("ok - readme figures: " + msg)


def bad(msg, why):
    global NFAIL
    NFAIL += 1
    print("FAIL - readme figures: %s: %s" % (msg, why))


def decimals(text):
    return len(text.split(".")[1]) if "." in text else 0


def same(shown, value):
    """shown (README text of a number) is value rounded as shown"""
    return shown.lstrip("+") == ("%.*f" % (decimals(shown), value)).lstrip("+")


def main():
    readme, log, where = sys.argv[1:4]
    text = open(readme, encoding="utf-8").read()
    printed = open(log, encoding="utf-8", errors="replace").read()
    summary = re.compile(r"^qdc: (\S+) -> (\S+): (mean ratio .*) \((.*), [0-9.]+s\)$")

    # 1. the CLI's last lines
    shown = [summary.match(l[4:]) for l in text.splitlines() if l.startswith("    qdc: ")]
    shown = [m for m in shown if m]
    if not shown:
        bad("summary lines", "README.md shows no 'qdc: IN -> OUT: mean ratio ...' line")
    for m in shown:
        runs = [summary.match(l.strip()) for l in printed.splitlines()]
        runs = [r for r in runs if r and r.group(1) == m.group(1) and r.group(2) == m.group(2)]
        if not runs:
            bad(m.group(2), "no command printed a summary for %s -> %s" % (m.group(1), m.group(2)))
        elif (runs[-1].group(3), runs[-1].group(4)) != (m.group(3), m.group(4)):
            bad(m.group(2), "README shows '%s (%s)', the run printed '%s (%s)'"
                % (m.group(3), m.group(4), runs[-1].group(3), runs[-1].group(4)))
        else:
            ok("%s -> %s prints what the README shows (%s; %s)" % (m.group(1), m.group(2), m.group(3), m.group(4)))

    # the outcome in words, word for word
    outcomes = [l[4:] for l in text.splitlines() if l.startswith("    qdc: outcome: ")]
    said = set(l.strip() for l in printed.splitlines())
    if not outcomes:
        bad("outcome", "README.md shows no 'qdc: outcome: ...' line")
    for o in outcomes:
        if o in said:
            ok("the outcome line is one a run printed (%s...)" % o[:60])
        else:
            near = [l for l in said if l.startswith("qdc: outcome: ")]
            bad("outcome", "README shows '%s', the runs printed %s" % (o, near))

    # 2. the histogram table and its summary, against the report it names
    name = re.search(r"from `([^`]+\.json)`:\n\n    dihedral ", text)
    if not name:
        bad("histogram", "no 'from `REPORT.json`:' before the dihedral table")
        return
    path = os.path.join(where, name.group(1))
    try:
        rep = json.load(open(path))
    except (OSError, ValueError) as e:
        bad("histogram", "cannot read %s: %s" % (name.group(1), e))
        return
    b, a = rep["before"], rep["after"]
    rows = re.findall(r"^ +(\d+)- *(\d+)°  #* +(\d+) +#* +(\d+)$", text, re.M)
    diffs = []
    for lo, hi, nb, na in rows:
        lo, hi = int(lo), int(hi)
        tb = sum(b["dihedral_histogram"][lo:hi])
        ta = sum(a["dihedral_histogram"][lo:hi])
        if (int(nb), int(na)) != (tb, ta):
            diffs.append("%d-%d: README %s/%s, report %d/%d" % (lo, hi, nb, na, tb, ta))
    if len(rows) != 18 or diffs:
        bad("histogram", "%d rows; %s" % (len(rows), "; ".join(diffs)))
    else:
        ok("the 18 rows of the dihedral table are %s's histograms (%d and %d angles)"
           % (name.group(1), sum(int(r[2]) for r in rows), sum(int(r[3]) for r in rows)))

    m = re.search(r"^    mean ratio (\S+) -> (\S+), worst (\S+) -> (\S+), dihedral (\S+)\.\.(\S+)° -> "
                  r"(\S+)\.\.(\S+)°\n    tets with an angle < 5°: (\d+) -> (\d+), > 175°: (\d+) -> (\d+)$",
                  text, re.M)
    if not m:
        bad("summary", "no 'mean ratio ... worst ... dihedral' and 'tets with an angle' lines")
        return
    want = [b["mean_ratio_mean"], a["mean_ratio_mean"], b["mean_ratio_min"], a["mean_ratio_min"],
            b["dihedral_min"], b["dihedral_max"], a["dihedral_min"], a["dihedral_max"]]
    counts = [b["n_dmin_lt_5"], a["n_dmin_lt_5"], b["n_dmax_gt_175"], a["n_dmax_gt_175"]]
    wrong = [(s, v) for s, v in zip(m.groups()[:8], want) if not same(s, v)]
    wrong += [(s, v) for s, v in zip(m.groups()[8:], counts) if int(s) != v]
    if wrong:
        bad("summary", "README vs report: " + ", ".join("%s vs %s" % w for w in wrong))
    else:
        ok("summary under the table is the report's: " + m.group(0).strip().replace("\n    ", "; "))
    m = re.search(r"moved by at most ([0-9.]+)% of the\s+bounding-box diagonal", text)
    if m:
        rel = 100 * rep["boundary_error"]["hausdorff_rel"]
        if same(m.group(1), rel):
            ok("boundary moved by at most %s%% of the diagonal, as the report's hausdorff_rel" % m.group(1))
        else:
            bad("boundary", "README %s%%, report %.4f%%" % (m.group(1), rel))


main()
sys.exit(1 if NFAIL else 0)
