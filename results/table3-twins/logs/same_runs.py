# Whether the runs of a second sweep folder equal the committed table3-twins runs bit for bit
# (ATE, keyframes, map points, frames tracked, loops, mean inliers), run key by run key:
# python3 logs/same_runs.py runs.csv OTHER/runs.csv
import csv, sys, collections
ours = {(r['sequence'], r['config'], r['seed']): r for r in csv.DictReader(open(sys.argv[1]))}
fields = ('ate_rmse', 'keyframes', 'map_points', 'tracked', 'loops', 'mean_inliers')
same, differ, missing = collections.Counter(), [], []
for r in csv.DictReader(open(sys.argv[2])):
    k = (r['sequence'], r['config'], r['seed'])
    if k not in ours:
        missing.append(k)
    elif all(r[f] == ours[k][f] for f in fields):
        same[r['sequence']] += 1
    else:
        differ.append(k)
print('equal:', dict(same))
print('differ:', differ)
print('not in the first folder:', missing)
