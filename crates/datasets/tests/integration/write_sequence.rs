//! A sequence written by `datasets::write::write_sequence` reads back through the project's own
//! readers to what was written: images (colour kept) and stamps bit for bit, depth to its
//! 16-bit step, the ground truth's every digit in the file, the camera; for the TUM and the
//! EuRoC layout; the extra files are written beside; an occupied
//! folder is refused and a failed write leaves nothing.

use datasets::write::write_sequence;
use datasets::{open_path, open_synth, DatasetError, Format};
use synth::{Generator, SynthConfig};

fn bits(xs: impl IntoIterator<Item = f64>) -> Vec<u64> {
    xs.into_iter().map(f64::to_bits).collect()
}

/// The numbers of the data lines of a TUM trajectory or EuRoC ground-truth file.
fn numbers(path: &std::path::Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split([' ', ',']).map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn round_trip(preset: &str, n: usize) {
    let gen = Generator::new(SynthConfig::preset(preset).unwrap(), 2);
    let (seq, frames) = open_synth(&gen, n);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(preset);
    let extra = [("note.txt", "what was done\n".to_string())];
    write_sequence(&seq, &frames, &out, &extra, None, |_| {}).unwrap();
    assert_eq!(
        std::fs::read_to_string(out.join("note.txt")).unwrap(),
        "what was done\n"
    );
    assert!(
        out.join("camera-orbslam2.yaml").is_file() && out.join("camera-orbslam3.yaml").is_file()
    );

    let (back, back_frames) = open_path(&out).unwrap();
    assert_eq!(back.format, seq.format, "{preset}");
    assert_eq!(back_frames.len(), n, "{preset}");
    let (c, d) = (&seq.camera, &back.camera);
    assert_eq!(
        (d.fx, d.fy, d.cx, d.cy, d.width, d.height),
        (c.fx, c.fy, c.cx, c.cy, c.width, c.height),
        "{preset}"
    );
    if seq.format == Format::EurocStereo {
        assert_eq!(d.bf.to_bits(), c.bf.to_bits(), "{preset}");
    }
    for i in 0..n {
        let (a, b) = (frames.read(i).unwrap(), back_frames.read(i).unwrap());
        assert_eq!(a.timestamp.to_bits(), b.timestamp.to_bits(), "{preset} {i}");
        assert_eq!(a.image.data, b.image.data, "{preset} frame {i}: grey");
        match (&a.colour, &b.colour) {
            (Some(x), Some(y)) => assert_eq!(x.data, y.data, "{preset} frame {i}: colour"),
            (None, None) => {}
            _ => panic!("{preset} frame {i}: colour kept or lost"),
        }
        match (&a.depth, &b.depth) {
            (Some(x), Some(y)) => {
                assert_eq!(x.data.len(), y.data.len());
                // Depth goes through the 16-bit PNG: equal to its quantisation step.
                let units = seq.depth_factor.unwrap_or(5000.0);
                for (p, q) in x.data.iter().zip(&y.data) {
                    assert!(
                        (p - q).abs() as f64 <= 0.5 / units + 1e-6,
                        "{preset} frame {i}: depth {p} read back as {q}"
                    );
                }
            }
            (None, None) => {}
            _ => panic!("{preset} frame {i}: depth kept or lost"),
        }
        match (&a.right, &b.right) {
            (Some(x), Some(y)) => assert_eq!(x.data, y.data, "{preset} frame {i}: right"),
            (None, None) => {}
            _ => panic!("{preset} frame {i}: right image kept or lost"),
        }
    }
    // The file holds every digit of the ground truth (EuRoC: stamps in whole nanoseconds that
    // read back to the same seconds); the readers re-normalise the quaternion, so a rotation
    // read back may differ in its last bit.
    let (g, h) = (seq.groundtruth.as_ref().unwrap(), back.groundtruth.unwrap());
    let file = match seq.format {
        Format::TumRgbd => out.join("groundtruth.txt"),
        Format::EurocStereo => out.join("mav0/state_groundtruth_estimate0/data.csv"),
    };
    let written = numbers(&file);
    assert_eq!(g.stamps.len(), written.len(), "{preset}");
    assert_eq!(g.stamps.len(), h.stamps.len(), "{preset}");
    for (k, line) in written.iter().enumerate() {
        let (p, q) = (&g.poses[k], &h.poses[k]);
        let t = p.translation.vector;
        let r = p.rotation.coords; // x, y, z, w
        let expected = match seq.format {
            Format::TumRgbd => vec![g.stamps[k], t.x, t.y, t.z, r.x, r.y, r.z, r.w],
            Format::EurocStereo => vec![t.x, t.y, t.z, r.w, r.x, r.y, r.z],
        };
        let line = match seq.format {
            Format::TumRgbd => &line[..],
            Format::EurocStereo => &line[1..],
        };
        assert_eq!(
            bits(line.iter().copied()),
            bits(expected),
            "{preset} pose {k}"
        );
        assert_eq!(
            g.stamps[k].to_bits(),
            h.stamps[k].to_bits(),
            "{preset} pose {k}"
        );
        assert_eq!(
            bits(p.translation.vector.iter().copied()),
            bits(q.translation.vector.iter().copied()),
            "{preset} pose {k}"
        );
        assert!(
            p.rotation.angle_to(&q.rotation) < 1e-12,
            "{preset} pose {k}"
        );
    }

    let again = write_sequence(&seq, &frames, &out, &[], None, |_| {});
    assert!(
        matches!(again, Err(DatasetError::OutputExists { .. })),
        "{again:?}"
    );
}

#[test]
fn a_tum_sequence_reads_back_as_written() {
    round_trip("kinect", 3);
}

#[test]
fn a_euroc_sequence_reads_back_as_written() {
    round_trip("stereo", 3);
}

#[test]
fn a_sequence_without_depth_is_refused_and_leaves_nothing() {
    let gen = Generator::new(SynthConfig::preset("stereo").unwrap(), 2);
    let (mut seq, frames) = open_synth(&gen, 2);
    // A stereo sequence's frames claimed as RGB-D: frame 0 has no depth image.
    seq.format = Format::TumRgbd;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad");
    let err = write_sequence(&seq, &frames, &out, &[], None, |_| {}).unwrap_err();
    assert!(err.to_string().contains("has no depth image"), "{err}");
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "staging left"
    );
}
