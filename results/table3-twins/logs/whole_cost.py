# The whole table3-twins sweep's cost, row by row, from what was measured: MH01, MH02, MH03 and
# MH05 from the log of the invocation that ran them (before cost.csv existed), the EuRoC rows
# after them from cost.csv, the TUM rows from their re-measure (logs/remeasure-tum/cost.csv:
# the same runs made again, bit for bit, by a binary that keeps its cost), fr3_nst from its
# control run (logs/control-fr3_nst.log). A row whose cost line covers fewer than its 50 runs
# (an invocation restarted inside the row: V202, and fr1_teddy of the re-measure) is composed:
# its missing runs are charged what its measured ones cost beyond the rendering (the twin's CPU
# s per frame in render-speed/) and the extraction (the log's "features of" line).
# python3 results/table3-twins/logs/whole_cost.py (from any folder)
import csv, re, os
os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
rows = {}
pat = re.compile(r"sweep: (\S+) done; .*? (\S+) elapsed.*?; (\d+) frames run in (\d+) CPU-s")
def secs(h):
    m = re.fullmatch(r"(?:(\d+)h)?(?:(\d+)m)?(\d+)s", h)
    a = [int(x or 0) for x in m.groups()]
    return a[0] * 3600 + a[1] * 60 + a[2]
prev = (0, 0, 0)
for line in open('logs/sweep-2026-11-29.log'):
    m = pat.search(line)
    if m:
        f, c, w = int(m.group(3)), int(m.group(4)), secs(m.group(2))
        rows[m.group(1)] = [f - prev[0], c - prev[1], w - prev[2], 'log']
        prev = (f, c, w)
for line in open('logs/control-fr3_nst.log'):
    m = pat.search(line)
    if m:
        rows[m.group(1)] = [int(m.group(3)), int(m.group(4)), secs(m.group(2)), 'control']
measured_runs = {}
for path, src in (('cost.csv', 'cost.csv'), ('logs/remeasure-tum/cost.csv', 're-measure')):
    if os.path.exists(path):
        for r in csv.DictReader(open(path)):
            rows[r['point']] = [int(r['frames']), float(r['cpu_s']), float(r['wall_s']), src]
            measured_runs[r['point']] = int(r['runs'])
render_s = {}
for line in open('../render-speed/README.md'):
    if line.startswith('## '):
        break  # the first table: the shipped renderer's CPU s per frame, "after"
    m = re.match(r"\| (twin_\w+) \| [\d.]+ \| ([\d.]+) \|", line)
    if m:
        render_s[m.group(1)] = float(m.group(2))
extraction = {}
for log in ('logs/sweep-2026-11-29b.log', 'logs/remeasure-tum/sweep.log'):
    if os.path.exists(log):
        for line in open(log):
            m = re.match(r"(twin_\w+): features of (\d+) frames in [\d.]+ s \(([\d.]+) (?:s of one core|CPU-s)", line)
            if m:
                extraction[m.group(1)] = (int(m.group(2)), float(m.group(3)))
for k, (f, c, w, src) in list(rows.items()):
    runs = measured_runs.get(k, 50)
    if runs < 50:
        frames, extract = extraction[k]
        per_run = (c - frames * render_s[k] - extract) / runs
        whole = c + (50 - runs) * per_run
        rows[k] = [frames * 50, whole, w * whole / c, f'composed ({runs} runs measured)']
print("| row | frames run | CPU-s | frames/s per core | wall s (cores busy) | from |")
print("|---|---|---|---|---|---|")
tf = tc = 0
for k, (f, c, w, src) in sorted(rows.items()):
    print(f"| {k} | {f:,} | {c:,.0f} | {f / c:.0f} | {w:,.0f} ({c / w:.1f}) | {src} |")
    tf += f; tc += c
print(f"| {len(rows)} rows | {tf:,} | {tc:,.0f} | {tf / tc:.1f} | | |")
print(f"on two busy cores: {tc / 2 / 3600:.2f} h")
