#!/usr/bin/env python3
"""Summarise a Rerun recording with Rerun's own decoder (the rerun-sdk package): for every
entity path, the frame indices it was logged at and, per row, the number of instances of its
first list-valued component (points of a Points2D, say). Prints JSON. Used by
tests/rerun_cli.rs to read back what `noisefree run --rerun` and `noisefree view` wrote.

Usage: rrd_summary.py FILE.rrd
"""
import hashlib
import json
import sys

from rerun.experimental import RrdReader


def main(path):
    out = {}
    for chunk in RrdReader(path).stream():
        batch = chunk.to_record_batch()
        entry = out.setdefault(
            chunk.entity_path,
            {"static": False, "frames": [], "instances": [], "components": [], "digests": [], "labels": []},
        )
        entry["static"] = entry["static"] or chunk.is_static
        names = batch.schema.names
        for n in names:
            if ":" in n and n not in entry["components"]:
                entry["components"].append(n)
        frames = batch.column("frame").to_pylist() if "frame" in names else [None] * batch.num_rows
        lists = sorted(
            (n for n in names if ":" in n),
            key=lambda n: (not n.endswith((":positions", ":strips", ":scalars", ":blob", ":buffer")), n),
        )
        counts = [None] * batch.num_rows
        if lists:
            col = batch.column(lists[0]).to_pylist()
            counts = [len(v) if isinstance(v, list) else (0 if v is None else 1) for v in col]
        blobs = [n for n in names if n.endswith(":blob")]
        if blobs:
            col = batch.column(blobs[0]).to_pylist()
            entry["digests"].extend(hashlib.md5(repr(v).encode()).hexdigest() for v in col)
        for n in names:
            if n.endswith(":labels"):
                for v in batch.column(n).to_pylist():
                    for label in v or []:
                        if label not in entry["labels"]:
                            entry["labels"].append(label)
        entry["frames"].extend(frames)
        entry["instances"].extend(counts)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1])
