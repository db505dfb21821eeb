# Per-row cost from a sweep log written before cost.csv existed: python3 cost_from_log.py sweep-2026-11-29.log
# Per-row cost of a sweep invocation from its log's "done" lines (cumulative frames, CPU-s, elapsed).
import re, sys
pat = re.compile(r"sweep: (\S+) done; (\d+)/\d+ runs recorded, (\S+) elapsed.*?; (\d+) frames run in (\d+) CPU-s")
def secs(h):
    m = re.fullmatch(r"(?:(\d+)h)?(?:(\d+)m)?(\d+)s", h); a = [int(x or 0) for x in m.groups()]
    return a[0]*3600 + a[1]*60 + a[2]
prev = (0, 0, 0)
tot = [0, 0, 0]
for line in open(sys.argv[1]):
    m = pat.search(line)
    if not m: continue
    row, wall, frames, cpu = m.group(1), secs(m.group(3)), int(m.group(4)), int(m.group(5))
    d = (frames - prev[0], cpu - prev[1], wall - prev[2]); prev = (frames, cpu, wall)
    print(f"{row:14s} frames run {d[0]:7d}  CPU {d[1]:6d} s  wall {d[2]:6d} s  {d[0]/d[1]:6.1f} frames/s per core  {d[1]/max(d[2],1):.2f} cores")
print(f"total          frames run {prev[0]:7d}  CPU {prev[1]:6d} s  wall {prev[2]:6d} s  {prev[0]/prev[1]:6.1f} frames/s per core")
