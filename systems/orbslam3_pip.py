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


def setting(text, key):
    """The value of `key: value` in an OpenCV YAML settings file, or None."""
    for line in text.splitlines():
        k, sep, v = line.partition(":")
        if sep and k.strip() == key:
            return v.split("#")[0].strip().strip('"')
    return None


def stereo_settings(path):
    """The settings ORB-SLAM3 1.0 reads for a stereo pair. A `Rectified` pair crashes it (its
    Settings printer dereferences the absent second calibration: a segmentation fault before
    the first frame), so a rectified pair is handed over as the `PinHole` pair it is: both
    cameras with camera 1's intrinsics and no distortion, camera 2 at (b, 0, 0) in camera 1's
    frame. ORB-SLAM3 then rectifies with identity rotations, a resampling of the same pixels.
    The rewritten file goes into the working directory (settings-pinhole.yaml)."""
    with open(path) as f:
        text = f.read()
    kind = setting(text, "Camera.type")
    if kind is None:
        fail(f"{path}: no Camera.type: not an ORB-SLAM3 1.0 settings file (File.version \"1.0\"); "
             "give the system `settings = \"orbslam3\"`")
    if kind == "PinHole" and setting(text, "Stereo.T_c1_c2") is None and "Stereo.T_c1_c2" not in text:
        fail(f"{path}: a PinHole stereo pair needs Stereo.T_c1_c2 (and Camera2.*)")
    if kind != "Rectified":
        return path
    vals = {}
    for k in ("Camera1.fx", "Camera1.fy", "Camera1.cx", "Camera1.cy", "Stereo.b"):
        v = setting(text, k)
        try:
            vals[k] = float(v)
        except (TypeError, ValueError):
            fail(f"{path}: Camera.type Rectified needs a number for {k}, got {v!r}")
    lines = []
    for line in text.splitlines():
        if line.split(":")[0].strip() in ("Camera.type", "Stereo.b"):
            continue
        lines.append(line)
    extra = ['Camera.type: "PinHole"']
    for cam in ("Camera1", "Camera2"):
        for k in ("fx", "fy", "cx", "cy"):
            extra.append(f"{cam}.{k}: {vals['Camera1.' + k]!r}")
        for k in ("k1", "k2", "p1", "p2"):
            extra.append(f"{cam}.{k}: 0.0")
    b = vals["Stereo.b"]
    extra += ["Stereo.T_c1_c2: !!opencv-matrix", "  rows: 4", "  cols: 4", "  dt: f",
              f"  data: [1.0, 0.0, 0.0, {b!r}, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, "
              "0.0, 0.0, 0.0, 1.0]"]
    # Camera1.* of the original are replaced by the block above.
    lines = [l for l in lines if not l.split(":")[0].strip().startswith("Camera1.")]
    head = 0
    while head < len(lines) and (lines[head].startswith("%") or lines[head].startswith("#")
                                 or not lines[head].strip() or lines[head].startswith("File.")):
        head += 1
    out = lines[:head] + extra + lines[head:]
    new = os.path.abspath("settings-pinhole.yaml")
    with open(new, "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"{path}: a Rectified pair (which crashes ORB-SLAM3 1.0's settings printer) handed "
          f"over as PinHole with identity rectification: {new}", flush=True)
    return new


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
    for p in (f for fr in frames[:1] for f in fr[1:]):
        if not os.path.isfile(p):
            fail(f"{p}: no such image (the first frame of {a.frames}; is {a.sequence} the "
                 f"{'TUM folder' if a.mode == 'rgbd' else 'folder holding mav0'}?)")
    settings = stereo_settings(a.settings) if a.mode == "stereo" else a.settings
    sensor = pos.Sensor.RGBD if a.mode == "rgbd" else pos.Sensor.STEREO
    t0 = time.time()
    slam = pos.Slam(a.vocabulary, settings, sensor, use_viewer=False)
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
