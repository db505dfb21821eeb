# Counts for the table3-twins reading, from `noisefree table --paper` output: python3 reading.py versus-baseline.csv
# Reading of a table3-twins versus-baseline.csv: per row, the twin's ORB-SLAM2 (ours) mean [CI]
# against the paper's ORB-SLAM2 figure (how hard the twin is), and per technique: whether the
# difference survives Holm, its sign, and whether the paper's figure lies inside our interval.
import csv, sys, collections
rows = list(csv.DictReader(open(sys.argv[1])))
orb = {r['sequence']: r for r in rows if r['config'] == 'orb'}
print("row | twin ORB mm [CI] | paper mm | paper/twin | verdict")
hard = collections.Counter()
for s, r in orb.items():
    m, lo, hi, p = (float(r[k]) * 1e3 for k in ('mean_m', 'ci95_lo_m', 'ci95_hi_m', 'paper_m'))
    # A twin on which most runs fail is harder than its real sequence, where ORB-SLAM2 ran through.
    if 2 * int(r['failed']) > int(r['runs']):
        v = 'harder (most runs fail)'
    else:
        v = 'as hard (paper inside CI)' if lo <= p <= hi else ('easier' if p > hi else 'harder')
    hard[v] += 1
    print(f"{s} | {m:.2f} [{lo:.2f}, {hi:.2f}] | {p:g} | {p/m:.1f}x | {v} | failed {r['failed']}")
print(hard)
surv = [r for r in rows if r['survives_holm'] == '1']
print(len([r for r in rows if r['config'] != 'orb']), 'comparisons;', len(surv), 'survive Holm:')
for r in surv:
    print('  ', r['sequence'], r['config'], f"{float(r['diff_pct']):+.1f} % [{float(r['diff_ci95_lo_pct']):+.1f}, {float(r['diff_ci95_hi_pct']):+.1f}]", 'p_holm', r['p_holm'])
# paper's claimed gains: paper_m < paper_orb_slam2_m; do we exclude them?
n = ex = inside = np_ = 0
for r in rows:
    if r['config'] == 'orb' or not r['paper_m'] or not r['diff_pct']:
        continue
    np_ += 1
    pm, po = float(r['paper_m']), float(r['paper_orb_slam2_m'])
    lo, hi = float(r['ci95_lo_m']) * 1e3, float(r['ci95_hi_m']) * 1e3
    if lo <= pm * 1e3 <= hi:
        inside += 1
    if pm < po:
        n += 1
        gain = (pm - po) / po * 100
        if gain < float(r['diff_ci95_lo_pct']):
            ex += 1
print(f"paper figure inside our interval: {inside} of {np_}; paper-claimed gains {n}, excluded by our interval {ex}")
