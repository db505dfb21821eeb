#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
#
# orbslam3_pip.py: ORB-SLAM3's `rgbd_tum` and `stereo_euroc` example programs, over the
# `pyorbslam3` wheel (PyPI, Linux x86-64: `pip install pyorbslam3 pillow`), so that the real
# ORB-SLAM3 runs as a noisefree external system (a `[systems.NAME]` definition, see
# systems/orbslam3-pip.toml) without building it.
#
# LICENCE: this file imports pyorbslam3, which is GPL-3.0 (it links ORB-SLAM3, GPL-3.0). It is
# therefore distributed under the GPL-3.0-or-later, separately from noisefree (MIT OR
# Apache-2.0): noisefree never imports or links it; it only runs it as a child process, as it
# runs any other SLAM program.
#
# Usage (the arguments of ORB-SLAM3's examples, plus options):
#   orbslam3_pip.py rgbd   VOCABULARY SETTINGS SEQUENCE ASSOCIATIONS [--pace] [--out FILE]
#   orbslam3_pip.py stereo VOCABULARY SETTINGS SEQUENCE TIMES        [--pace] [--out FILE]
# rgbd: SEQUENCE is a TUM RGB-D folder, ASSOCIATIONS lines `t_rgb rgb/x.png t_depth depth/x.png`.
# stereo: SEQUENCE is the folder holding mav0/ (rectified or raw: the settings file says), TIMES
# the cam0 stamps in nanoseconds, one a line (images mav0/cam0/data/<ns>.png, cam1 the same).
# The trajectory is written as TUM (`stamp tx ty tz qx qy qz qw`, seconds) to CameraTrajectory.txt
# in the working directory (--out to change it). Headless (no viewer); without --pace frames are
# fed as fast as ORB-SLAM3 takes them (a sweep's speed), with --pace at the sequence's rate as
# the stock examples do. Each frame's tracking time and state go to standard output, a summary
# (median and mean tracking time, states) at the end.

import argparse
import os
import sys
import time


def fail(msg):
    print(f"orbslam3_pip.py: {msg}", file=sys.stderr)
    sys.exit(2)


try:
    import numpy as np
    from PIL import Image
    import pyorbslam3 as pos
except ImportError as e:  # pragma: no cover - depends on the environment
    fail(f"{e}: install the wheel and Pillow into the Python running this script "
         "(python3 -m venv venv && venv/bin/pip install pyorbslam3 pillow), and name that "
         "Python in the system definition's command")


def read_image(path, depth=False):
    if not os.path.isfile(path):
        fail(f"{path}: no such image")
    try:
        img = Image.open(path)
        if depth:
            # ORB-SLAM3 scales raw depth units by 1 / DepthMapFactor itself.
            return np.asarray(img, dtype=np.uint16).astype(np.float32)
        if img.mode not in ("L", "RGB"):
            img = img.convert("RGB")
        return np.ascontiguousarray(np.asarray(img))
    except Exception as e:  # a corrupt file: say which
        fail(f"{path}: {e}")


def rgbd_frames(seq, assoc):
    out = []
    with open(assoc) as f:
        for n, line in enumerate(f, 1):
            parts = line.split()
            if not parts or parts[0].startswith("#"):
                continue
            if len(parts) < 4:
                fail(f"{assoc}:{n}: expected `t_rgb rgb_file t_depth depth_file`")
            out.append((float(parts[0]), os.path.join(seq, parts[1]), os.path.join(seq, parts[3])))
    return out


def stereo_frames(seq, times):
    mav0 = os.path.join(seq, "mav0") if os.path.isdir(os.path.join(seq, "mav0")) else seq
    out = []
    with open(times) as f:
        for n, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            if not s.isdigit():
                fail(f"{times}:{n}: expected a stamp in nanoseconds")
            out.append((int(s) * 1e-9, os.path.join(mav0, "cam0", "data", s + ".png"),
                        os.path.join(mav0, "cam1", "data", s + ".png")))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("mode", choices=["rgbd", "stereo"])
    ap.add_argument("vocabulary")
    ap.add_argument("settings")
    ap.add_argument("sequence")
    ap.add_argument("frames", help="associations (rgbd) or times in ns (stereo)")
    ap.add_argument("--pace", action="store_true", help="feed frames at the sequence's rate")
    ap.add_argument("--out", default="CameraTrajectory.txt")
    a = ap.parse_args()
    for p in (a.vocabulary, a.settings, a.frames):
        if not os.path.isfile(p):
            fail(f"{p}: no such file")
    frames = rgbd_frames(a.sequence, a.frames) if a.mode == "rgbd" else stereo_frames(a.sequence, a.frames)
    if not frames:
        fail(f"{a.frames}: no frames")
    sensor = pos.Sensor.RGBD if a.mode == "rgbd" else pos.Sensor.STEREO
    t0 = time.time()
    slam = pos.Slam(a.vocabulary, a.settings, sensor, use_viewer=False)
    print(f"loaded vocabulary {a.vocabulary} and settings in {time.time() - t0:.1f} s", flush=True)
    times, states = [], {}
    start = time.time()
    for i, (t, f1, f2) in enumerate(frames):
        if a.mode == "rgbd":
            img, dep = read_image(f1), read_image(f2, depth=True)
            tic = time.perf_counter()
            r = slam.track_rgbd(img, dep, t)
        else:
            left, right = read_image(f1), read_image(f2)
            tic = time.perf_counter()
            r = slam.track_stereo(left, right, t)
        dt = time.perf_counter() - tic
        times.append(dt)
        state = str(r.state).split(".")[-1] if hasattr(r, "state") else str(getattr(r, "tracking_state", "?"))
        states[state] = states.get(state, 0) + 1
        print(f"frame {i} t {t:.6f} track_ms {dt * 1e3:.2f} state {state}", flush=True)
        if a.pace and i + 1 < len(frames):
            wait = (frames[i + 1][0] - t) - dt
            if wait > 0:
                time.sleep(wait)
    wall = time.time() - start
    slam.shutdown()
    slam.save_trajectory_tum(a.out)
    ts = sorted(times)
    print(f"{len(frames)} frames in {wall:.1f} s; tracking median {ts[len(ts) // 2] * 1e3:.1f} ms, "
          f"mean {sum(ts) / len(ts) * 1e3:.1f} ms; states {states}", flush=True)


if __name__ == "__main__":
    main()
