//! Camera settings files (ORB-SLAM2's and ORB-SLAM3's YAML) written from every camera of the
//! catalog: they parse as YAML, carry the values of ORB-SLAM2's own TUM1/2/3.yaml and
//! EuRoC.yaml (and ORB-SLAM3's) for the real cameras, and read back to the same camera, bit
//! for bit; a real EuRoC folder opened with its exported settings is the folder as read from
//! its `sensor.yaml` files; bad files are refused with their name and line.

use datasets::settings::{read_settings, write_settings, CameraSettings, SettingsFormat};
use datasets::{open_euroc_with, open_path, open_path_with_settings, CameraId, EurocOptions};
use rayon::prelude::*;
use slam_core::SensorKind;
use std::path::{Path, PathBuf};

fn euroc_dir() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    [
        std::env::var_os("NOISEFREE_EUROC_HEAD").map(PathBuf::from),
        Some(here.join("../../../shared/data/euroc_v101_head")),
        Some(PathBuf::from("/work/shared/data/euroc_v101_head")),
    ]
    .into_iter()
    .flatten()
    .find(|p| p.join("mav0").is_dir())
    .expect("real EuRoC frames not found: set NOISEFREE_EUROC_HEAD to shared/data/euroc_v101_head")
}

/// Parses a settings file with a YAML library. OpenCV's `%YAML:1.0` header line is not a YAML
/// 1.1/1.2 directive (the colon), so it is dropped first; everything else must be YAML.
fn yaml(text: &str) -> serde_yaml::Mapping {
    let first = text.lines().next().unwrap();
    assert_eq!(first, "%YAML:1.0", "OpenCV needs this first line");
    let body: String = text.lines().skip(1).collect::<Vec<_>>().join("\n");
    match serde_yaml::from_str::<serde_yaml::Value>(&body).expect("valid YAML") {
        serde_yaml::Value::Mapping(m) => m,
        other => panic!("not a mapping: {other:?}"),
    }
}

fn num(m: &serde_yaml::Mapping, key: &str) -> f64 {
    m.get(key)
        .unwrap_or_else(|| panic!("no {key}"))
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number"))
}

/// An ORB-SLAM3 real must be written as a real (its Settings refuses `40` for a float), an
/// integer as an integer.
fn is_real(text: &str, key: &str) -> bool {
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("{key}:")))
        .unwrap_or_else(|| panic!("no {key}"));
    let v = line.split_once(':').unwrap().1.trim();
    v.contains('.') || v.contains('e')
}

/// The data of an `!!opencv-matrix` entry.
fn matrix(m: &serde_yaml::Mapping, key: &str) -> Vec<f64> {
    let v = m.get(key).unwrap_or_else(|| panic!("no {key}"));
    // serde_yaml resolves the `!!` shorthand of a tag it does not know to the plain mapping.
    let inner = match v {
        serde_yaml::Value::Tagged(t) => t.value.as_mapping().unwrap(),
        serde_yaml::Value::Mapping(m) => m,
        other => panic!("{key} is not a matrix: {other:?}"),
    };
    let rows = inner.get("rows").unwrap().as_u64().unwrap() as usize;
    let cols = inner.get("cols").unwrap().as_u64().unwrap() as usize;
    let data: Vec<f64> = inner
        .get("data")
        .unwrap()
        .as_sequence()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(data.len(), rows * cols, "{key}");
    data
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

/// ORB-SLAM2's TUM1/2/3.yaml: (fx, fy, cx, cy, k1, k2, p1, p2, k3, DepthMapFactor) and
/// ORB-SLAM3's Stereo.b.
const TUM: [(CameraId, [f64; 10], f64); 3] = [
    (
        CameraId::Fr1,
        [
            517.306408, 516.469215, 318.643040, 255.313989, 0.262383, -0.953104, -0.005358,
            0.002628, 1.163314, 5000.0,
        ],
        0.07732,
    ),
    (
        CameraId::Fr2,
        [
            520.908620, 521.007327, 325.141442, 249.701764, 0.231222, -0.784899, -0.003257,
            -0.000105, 0.917205, 5208.0,
        ],
        0.0767,
    ),
    (
        CameraId::Fr3,
        [535.4, 539.2, 320.1, 247.6, 0.0, 0.0, 0.0, 0.0, 0.0, 5000.0],
        0.0747,
    ),
];

#[test]
fn tum_cameras_carry_orbslam2_and_orbslam3_values() {
    for (id, v, b) in TUM {
        let cam = id.tum_camera().unwrap();
        let s = CameraSettings::of_camera(&cam, Some(id.orbslam2_depth_factor()), None);
        let text = write_settings(&s, SettingsFormat::Orbslam2, "test");
        let m = yaml(&text);
        for (k, want) in ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"]
            .iter()
            .zip(v)
        {
            assert_eq!(num(&m, &format!("Camera.{k}")), want, "{id:?} Camera.{k}");
        }
        assert_eq!(num(&m, "DepthMapFactor"), v[9], "{id:?}");
        for (k, want) in [
            ("Camera.bf", 40.0),
            ("ThDepth", 40.0),
            ("Camera.fps", 30.0),
            ("Camera.width", 640.0),
            ("Camera.height", 480.0),
            ("Camera.RGB", 1.0),
            ("ORBextractor.nFeatures", 1000.0),
            ("ORBextractor.scaleFactor", 1.2),
            ("ORBextractor.nLevels", 8.0),
            ("ORBextractor.iniThFAST", 20.0),
            ("ORBextractor.minThFAST", 7.0),
            ("Viewer.ViewpointF", 500.0),
        ] {
            assert_eq!(num(&m, k), want, "{id:?} {k}");
        }
        assert!(m.get("LEFT.K").is_none(), "no rectification for RGB-D");
        let back = read_settings(&write(&text, "o2.yaml"), SensorKind::Rgbd).unwrap();
        assert_eq!(
            back.camera, cam,
            "{id:?}: the camera reads back bit for bit"
        );
        assert_eq!(back.depth_factor, Some(v[9]));

        let text3 = write_settings(&s, SettingsFormat::Orbslam3, "test");
        let m3 = yaml(&text3);
        assert_eq!(m3.get("File.version").unwrap().as_str(), Some("1.0"));
        assert_eq!(m3.get("Camera.type").unwrap().as_str(), Some("PinHole"));
        for (k, want) in ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"]
            .iter()
            .zip(v)
        {
            assert_eq!(
                num(&m3, &format!("Camera1.{k}")),
                want,
                "{id:?} Camera1.{k}"
            );
        }
        // ORB-SLAM3's files round bf / fx (40 / 520.908620 = 0.076789 is written 0.0767).
        close(num(&m3, "Stereo.b"), b, 1e-4, "Stereo.b");
        assert_eq!(num(&m3, "RGBD.DepthMapFactor"), v[9]);
        assert_eq!(num(&m3, "Stereo.ThDepth"), 40.0);
        assert_eq!(num(&m3, "Camera.fps"), 30.0);
        for k in [
            "Stereo.b",
            "Stereo.ThDepth",
            "RGBD.DepthMapFactor",
            "Camera1.fx",
        ] {
            assert!(is_real(&text3, k), "{k} must be written as a real");
        }
        for k in [
            "Camera.fps",
            "Camera.width",
            "Camera.RGB",
            "ORBextractor.nLevels",
        ] {
            assert!(!is_real(&text3, k), "{k} must be written as an integer");
        }
        let back3 = read_settings(&write(&text3, "o3.yaml"), SensorKind::Rgbd).unwrap();
        assert_eq!(back3.camera, cam, "{id:?}: ORB-SLAM3's file reads back");
    }
}

fn write(text: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nf-settings-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("{}-{name}", text.len()));
    std::fs::write(&p, text).unwrap();
    p
}

/// ORB-SLAM2's EuRoC.yaml, LEFT.R and RIGHT.R.
const LEFT_R: [f64; 9] = [
    0.999966347530033,
    -0.001422739138722922,
    0.008079580483432283,
    0.001365741834644127,
    0.9999741760894847,
    0.007055629199258132,
    -0.008089410156878961,
    -0.007044357138835809,
    0.9999424675829176,
];
const RIGHT_R: [f64; 9] = [
    0.9999633526194376,
    -0.003625811871560086,
    0.007755443660172947,
    0.003680398547259526,
    0.9999684752771629,
    -0.007035845251224894,
    -0.007729688520722713,
    0.007064130529506649,
    0.999945173484644,
];

#[test]
fn real_euroc_settings_carry_orbslam2_s_euroc_yaml() {
    let dir = euroc_dir();
    let (seq, _) = open_path(&dir).unwrap();
    let s = CameraSettings::of_sequence(&seq);
    let text = write_settings(&s, SettingsFormat::Orbslam2, "V1_01");
    let m = yaml(&text);
    assert!(
        text.contains("LEFT.R: !!opencv-matrix\n"),
        "OpenCV's matrix tag"
    );
    close(num(&m, "Camera.fx"), 435.2046959714599, 1e-3, "fx");
    close(num(&m, "Camera.fy"), 435.2046959714599, 1e-3, "fy");
    close(num(&m, "Camera.cx"), 367.4517211914062, 1e-3, "cx");
    close(num(&m, "Camera.cy"), 252.2008514404297, 1e-3, "cy");
    close(num(&m, "Camera.bf"), 47.90639384423901, 1e-3, "bf");
    assert_eq!(num(&m, "Camera.k1"), 0.0);
    assert_eq!(num(&m, "ThDepth"), 35.0);
    assert_eq!(num(&m, "Camera.fps"), 20.0);
    assert_eq!(num(&m, "ORBextractor.nFeatures"), 1200.0);
    assert_eq!(
        (num(&m, "LEFT.width"), num(&m, "LEFT.height")),
        (752.0, 480.0)
    );
    assert_eq!(
        matrix(&m, "LEFT.K"),
        vec![458.654, 0.0, 367.215, 0.0, 457.296, 248.375, 0.0, 0.0, 1.0]
    );
    assert_eq!(
        matrix(&m, "LEFT.D"),
        vec![-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0]
    );
    assert_eq!(
        matrix(&m, "RIGHT.K"),
        vec![457.587, 0.0, 379.999, 0.0, 456.134, 255.238, 0.0, 0.0, 1.0]
    );
    assert_eq!(
        matrix(&m, "RIGHT.D"),
        vec![-0.28368365, 0.07451284, -0.00010473, -3.555907e-05, 0.0]
    );
    for (got, want) in matrix(&m, "LEFT.R").iter().zip(LEFT_R) {
        close(*got, want, 1e-6, "LEFT.R");
    }
    for (got, want) in matrix(&m, "RIGHT.R").iter().zip(RIGHT_R) {
        close(*got, want, 1e-6, "RIGHT.R");
    }
    let p = matrix(&m, "RIGHT.P");
    close(p[3], -47.90639384423901, 1e-3, "RIGHT.P Tx");
    close(p[0], 435.2046959714599, 1e-3, "RIGHT.P fx");

    // ORB-SLAM3's EuRoC.yaml: the raw pair and T_c1_c2, which it rectifies itself.
    let text3 = write_settings(&s, SettingsFormat::Orbslam3, "V1_01");
    let m3 = yaml(&text3);
    assert_eq!(m3.get("Camera.type").unwrap().as_str(), Some("PinHole"));
    assert_eq!(num(&m3, "Camera1.fx"), 458.654);
    assert_eq!(num(&m3, "Camera2.cx"), 379.999);
    assert_eq!(num(&m3, "Camera2.p2"), -3.555907e-05);
    assert_eq!(num(&m3, "Camera.fps"), 20.0);
    let t = matrix(&m3, "Stereo.T_c1_c2");
    for (got, want) in t.iter().zip([
        0.999997256477797,
        -0.002317135723275,
        -0.000343393120620,
        0.110074137800478,
        0.002312067192432,
        0.999898048507103,
        -0.014090668452683,
        -0.000156612054392,
    ]) {
        close(*got, want, 1e-6, "T_c1_c2");
    }
    assert!(text3.contains("dt: f"), "ORB-SLAM3 reads T_c1_c2 as floats");

    // Opened with its own exported settings, the folder is the folder: same camera, same
    // body extrinsic, same rectified images.
    let path = write(&text, "euroc.yaml");
    let (with, frames_with) = open_path_with_settings(&dir, &path).unwrap();
    let (_, frames) = open_euroc_with(&dir, &EurocOptions::default()).unwrap();
    assert_eq!(with.camera, seq.camera);
    assert_eq!(with.t_bs, seq.t_bs);
    for i in [0, 50] {
        let (a, b) = (frames_with.read(i).unwrap(), frames.read(i).unwrap());
        assert_eq!(a.image, b.image, "frame {i} left");
        assert_eq!(a.right, b.right, "frame {i} right");
    }
    // ORB-SLAM3's raw pair, rectified by our Bouguet: the same camera to well under a pixel.
    let path3 = write(&text3, "euroc3.yaml");
    let (with3, _) = open_path_with_settings(&dir, &path3).unwrap();
    close(
        with3.camera.fx,
        seq.camera.fx,
        1e-3,
        "fx from ORB-SLAM3's pair",
    );
    close(
        with3.camera.bf,
        seq.camera.bf,
        1e-3,
        "bf from ORB-SLAM3's pair",
    );
}

#[test]
fn every_preset_s_camera_reads_back_bit_for_bit() {
    // On every core: building a twin's generator solves its path (most of this test's time).
    let presets: Vec<synth::Preset> = synth::Preset::all().collect();
    presets.par_iter().for_each(|&preset| {
        let gen = synth::Generator::new(preset.config(), 0);
        let (seq, _) = datasets::open_synth(&gen, 1);
        let s = CameraSettings::of_sequence(&seq);
        for format in [SettingsFormat::Orbslam2, SettingsFormat::Orbslam3] {
            let text = write_settings(&s, format, preset.name());
            let m = yaml(&text);
            assert!(m.len() > 20, "{}: {} entries", preset.name(), m.len());
            let back = read_settings(
                &write(&text, &format!("{}-{}.yaml", preset.name(), format.name())),
                seq.camera.sensor,
            )
            .unwrap();
            let what = format!("{} ({})", preset.name(), format.name());
            match (format, &s.rig) {
                // ORB-SLAM3 takes a raw pair unrectified: we rectify it again on reading.
                (SettingsFormat::Orbslam3, Some(rig)) if rig.left.distortion.k1 != 0.0 => {
                    close(back.camera.fx, seq.camera.fx, 1e-6, &what);
                }
                _ => assert_eq!(back.camera, seq.camera, "{what}"),
            }
            assert_eq!(back.depth_factor, seq.depth_factor, "{what}");
            if format == SettingsFormat::Orbslam2 {
                // The file places no camera in the body frame: everything else must survive.
                let unplaced = |r: &Option<datasets::settings::StereoRig>| {
                    r.clone().map(|mut r| {
                        r.left.t_bs = nalgebra::Isometry3::identity();
                        r.right.t_bs = nalgebra::Isometry3::identity();
                        r
                    })
                };
                assert_eq!(
                    unplaced(&back.rig),
                    unplaced(&s.rig),
                    "{what}: rectification"
                );
            }
        }
    });
}

#[test]
fn bad_settings_files_are_refused_with_their_name() {
    let base = CameraSettings::of_camera(&CameraId::Fr1.tum_camera().unwrap(), None, None);
    let text = write_settings(&base, SettingsFormat::Orbslam2, "t");
    let cases = [
        (text.replace("Camera.fx:", "Camera.fz:"), "Camera.fx"),
        (text.replace("ThDepth: 40.0", "ThDepth: forty"), "forty"),
        ("just words\n".to_string(), "not an ORB-SLAM2"),
        // Values that parse but are out of range (issue 45), named with line and range.
        (
            text.replace(
                "ORBextractor.scaleFactor: 1.2",
                "ORBextractor.scaleFactor: 0.5",
            ),
            "ORBextractor.scaleFactor = 0.5: must be > 1",
        ),
        (
            text.replace("ORBextractor.nLevels: 8", "ORBextractor.nLevels: 100000"),
            "ORBextractor.nLevels = 100000: must be in 1..=32",
        ),
        (text.replace("Camera.fx: ", "Camera.fx: -"), "Camera.fx = -"),
        (
            text.replace("Camera.width: 640", "Camera.width: 4000000000"),
            "Camera.width = 4000000000: must be <= 8192",
        ),
        (
            text.replace(
                "Camera.bf: 40.0",
                "Camera.bf: !!opencv-matrix\n   rows: 1\n   cols: 2\n   data: [1]",
            ),
            "Camera.bf",
        ),
    ];
    for (i, (bad, want)) in cases.iter().enumerate() {
        let p = write(bad, &format!("bad{i}.yaml"));
        let e = read_settings(&p, SensorKind::Rgbd).unwrap_err().to_string();
        assert!(
            e.contains(p.file_name().unwrap().to_str().unwrap()) && e.contains(want),
            "case {i}: {e}"
        );
    }
    let missing = read_settings(Path::new("/nonexistent/TUM1.yaml"), SensorKind::Rgbd)
        .unwrap_err()
        .to_string();
    assert!(missing.contains("TUM1.yaml"), "{missing}");
    // ORB-SLAM3's fisheye model is not one we read.
    let kb =
        write_settings(&base, SettingsFormat::Orbslam3, "t").replace("PinHole", "KannalaBrandt8");
    let e = read_settings(&write(&kb, "kb.yaml"), SensorKind::Rgbd)
        .unwrap_err()
        .to_string();
    assert!(e.contains("KannalaBrandt8"), "{e}");
}
