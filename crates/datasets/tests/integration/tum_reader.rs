//! TUM RGB-D reader on small folders written by the test: the happy path, and every kind of
//! bad input the issue lists (each must be a clear error naming the file, never a panic).

use crate::common;

use common::{small_camera, write_tum};
use datasets::{load_path, load_tum, load_tum_with, Catalog, DatasetError, Format, TumOptions};

#[test]
fn reads_frames_depth_and_groundtruth() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rgbd_dataset_freiburg3_test");
    write_tum(&dir, 5, 32, 24);
    let seq = load_tum(&dir, Some(small_camera(32, 24))).unwrap();
    assert_eq!(seq.format, Format::TumRgbd);
    assert_eq!(seq.name, "rgbd_dataset_freiburg3_test");
    assert_eq!(seq.len(), 5);
    for (i, f) in seq.frames.iter().enumerate() {
        assert!((f.timestamp - (1000.0 + i as f64 / 30.0)).abs() < 1e-6);
        assert!(f.image.data.iter().all(|&v| v == 10 + i as u8));
        let d = f.depth.as_ref().unwrap();
        let expect = (5000 + i) as f32 / 5000.0;
        assert!(d.data.iter().all(|&v| (v - expect).abs() < 1e-6));
        assert!(f.right.is_none());
    }
    let gt = seq.groundtruth.as_ref().unwrap();
    assert_eq!(gt.stamps.len(), 5);
    assert!((gt.poses[3].translation.vector.x - 0.03).abs() < 1e-12);
    assert_eq!(seq.image_bytes(), 5 * 32 * 24 * 5);
    // load_path detects the layout.
    let again = load_tum(&dir, Some(small_camera(32, 24))).unwrap();
    assert_eq!(again.frames[2].image, seq.frames[2].image);
}

/// TUM's motion-capture ground truth repeats a stamp now and then (fr2_desk, line 10863): the
/// folder loads, the ground truth is read as evaluate_ate.py reads it (last line of a repeated
/// stamp wins), and the sequence carries one note naming the file and line.
#[test]
fn groundtruth_with_repeated_stamp_loads_with_a_note() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 3, 16, 12);
    let gt = dir.join("groundtruth.txt");
    let mut text = std::fs::read_to_string(&gt).unwrap();
    let last = text.lines().rfind(|l| !l.starts_with('#')).unwrap();
    let stamp = last.split_whitespace().next().unwrap().to_string();
    text.push_str(&format!("{stamp} 9 9 9 0 0 0 1\n"));
    std::fs::write(&gt, &text).unwrap();
    let line = text.lines().count();
    let seq = load_tum(&dir, Some(small_camera(16, 12))).unwrap();
    let g = seq.groundtruth.as_ref().unwrap();
    assert_eq!(g.len(), 3);
    assert_eq!(g.poses[2].translation.vector.x, 9.0);
    assert_eq!(seq.notes.len(), 1, "{:?}", seq.notes);
    assert!(
        seq.notes[0].contains(&format!(
            "groundtruth.txt: 1 repeated stamp (first at line {line})"
        )),
        "{:?}",
        seq.notes
    );
}

#[test]
fn depth_factor_and_association_file_are_honoured() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 3, 16, 12);
    // associations.txt takes precedence: pair rgb 0 with depth 2 only.
    let rgb0 = 1000.0;
    let d2 = 1000.0 + 2.0 / 30.0 + 0.005;
    std::fs::write(
        dir.join("associations.txt"),
        format!("{rgb0:.6} rgb/{rgb0:.6}.png {d2:.6} depth/{d2:.6}.png\n"),
    )
    .unwrap();
    let opts = TumOptions {
        camera: Some(small_camera(16, 12)),
        depth_factor: Some(5208.0),
        ..TumOptions::default()
    };
    let seq = load_tum_with(&dir, &opts).unwrap();
    assert_eq!(seq.len(), 1);
    let d = seq.frames[0].depth.as_ref().unwrap().data[0];
    assert!((d - 5002.0 / 5208.0).abs() < 1e-6, "{d}");
}

#[test]
fn missing_rgb_txt() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 2, 16, 12);
    std::fs::remove_file(dir.join("rgb.txt")).unwrap();
    let e = load_tum(&dir, Some(small_camera(16, 12))).unwrap_err();
    assert!(matches!(e, DatasetError::Missing { .. }), "{e}");
    assert!(e.to_string().contains("rgb.txt"), "{e}");
    // load_path cannot even tell the layout and says what it looked for.
    let e = load_path(&dir).unwrap_err().to_string();
    assert!(e.contains("rgb.txt"), "{e}");
}

#[test]
fn listed_png_that_does_not_exist() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 3, 16, 12);
    let gone = dir.join(format!("rgb/{:.6}.png", 1000.0 + 1.0 / 30.0));
    std::fs::remove_file(&gone).unwrap();
    let e = load_tum(&dir, Some(small_camera(16, 12))).unwrap_err();
    assert!(matches!(e, DatasetError::Missing { .. }), "{e}");
    assert!(e.to_string().contains(&gone.display().to_string()), "{e}");
}

#[test]
fn eight_bit_depth_png() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 2, 16, 12);
    let p = dir.join(format!("depth/{:.6}.png", 1000.005));
    image::GrayImage::from_pixel(16, 12, image::Luma([5]))
        .save(&p)
        .unwrap();
    let e = load_tum(&dir, Some(small_camera(16, 12))).unwrap_err();
    assert!(matches!(e, DatasetError::DepthFormat { .. }), "{e}");
    let s = e.to_string();
    assert!(
        s.contains("16-bit") && s.contains("8-bit grey") && s.contains("1000.005000.png"),
        "{s}"
    );
}

#[test]
fn truncated_png() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 2, 16, 12);
    let p = dir.join(format!("rgb/{:.6}.png", 1000.0));
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_tum(&dir, Some(small_camera(16, 12))).unwrap_err();
    assert!(matches!(e, DatasetError::Decode { .. }), "{e}");
    assert!(e.to_string().contains("1000.000000.png"), "{e}");
}

#[test]
fn mismatched_image_sizes() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 2, 16, 12);
    // Depth smaller than its rgb image.
    let p = dir.join(format!("depth/{:.6}.png", 1000.005));
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(8, 12, image::Luma([1]))
        .save(&p)
        .unwrap();
    let e = load_tum(&dir, Some(small_camera(16, 12))).unwrap_err();
    let DatasetError::SizeMismatch {
        found_w,
        expected_w,
        ..
    } = &e
    else {
        panic!("{e}")
    };
    assert_eq!((*found_w, *expected_w), (8, 16));
    assert!(e.to_string().contains("depth/1000.005000.png"), "{e}");
    // Images that do not match the camera (the default fr3 camera is 640x480).
    let dir2 = tmp.path().join("seq2");
    write_tum(&dir2, 1, 16, 12);
    let e = load_tum(&dir2, None).unwrap_err().to_string();
    assert!(e.contains("16x12") && e.contains("640x480"), "{e}");
}

#[test]
fn malformed_list_line_names_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write_tum(&dir, 2, 16, 12);
    let mut txt = std::fs::read_to_string(dir.join("depth.txt")).unwrap();
    txt.push_str("12x.5 depth/x.png\n");
    std::fs::write(dir.join("depth.txt"), txt).unwrap();
    let e = load_tum(&dir, Some(small_camera(16, 12)))
        .unwrap_err()
        .to_string();
    assert!(e.contains("depth.txt:6") && e.contains("12x.5"), "{e}");
}

#[test]
fn unknown_sequence_name_suggests() {
    let e = Catalog::embedded().get("fr1_xzy").unwrap_err().to_string();
    assert!(
        e.contains("unknown sequence `fr1_xzy`") && e.contains("fr1_xyz"),
        "{e}"
    );
}
