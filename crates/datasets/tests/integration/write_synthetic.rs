//! The TUM and EuRoC folders written from a generator's frames (`datasets::write`) read back,
//! with plain PNG and text parsing independent of the project's dataset readers, to exactly the
//! in-memory frames; a folder that exists is never overwritten.

use std::fs;
use std::path::{Path, PathBuf};

use datasets::write::write_synthetic;
use datasets::DatasetError;
use nalgebra::{Isometry3, Matrix4, Quaternion, Translation3, UnitQuaternion};
use synth::{Generator, SynthConfig};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("datasets-write-test-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    d
}

fn lines(p: &Path) -> Vec<String> {
    fs::read_to_string(p)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn tum_folder_reads_back_identically() {
    let gen = Generator::new(SynthConfig::preset("walking").unwrap(), 3);
    let dir = temp_dir("tum");
    let n = 3;
    write_synthetic(&gen, n, &dir, |_| {}).unwrap();
    let rgb_txt = lines(&dir.join("rgb.txt"));
    let depth_txt = lines(&dir.join("depth.txt"));
    let gt = lines(&dir.join("groundtruth.txt"));
    let assoc = lines(&dir.join("associations.txt"));
    assert_eq!(rgb_txt[2], "# timestamp filename");
    assert_eq!(gt[2], "# timestamp tx ty tz qx qy qz qw");
    assert_eq!(
        (rgb_txt.len(), depth_txt.len(), gt.len(), assoc.len()),
        (n + 3, n + 3, n + 3, n)
    );
    for i in 0..n {
        let f = gen.frame(i);
        let s = format!("{:.6}", f.timestamp);
        assert_eq!(rgb_txt[3 + i], format!("{s} rgb/{s}.png"));
        assert_eq!(depth_txt[3 + i], format!("{s} depth/{s}.png"));
        assert_eq!(assoc[i], format!("{s} rgb/{s}.png {s} depth/{s}.png"));
        // Colour PNG: 8-bit RGB, same bytes.
        let rgb = image::open(dir.join(format!("rgb/{s}.png"))).unwrap();
        assert!(matches!(rgb, image::DynamicImage::ImageRgb8(_)));
        assert_eq!(rgb.to_rgb8().into_raw(), *f.rgb.as_ref().unwrap());
        // Depth PNG: 16-bit grey, value / 5000 = metres, same values.
        let depth = image::open(dir.join(format!("depth/{s}.png"))).unwrap();
        let depth = match depth {
            image::DynamicImage::ImageLuma16(d) => d,
            other => panic!("depth PNG is {:?}", other.color()),
        };
        let back: Vec<f32> = depth
            .into_raw()
            .iter()
            .map(|&v| (v as f64 / 5000.0) as f32)
            .collect();
        assert_eq!(back, f.depth.as_ref().unwrap().data);
        // Ground truth: the exact pose.
        let v: Vec<f64> = gt[3 + i].split(' ').map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), 8);
        assert!((v[0] - f.timestamp).abs() < 1e-6);
        let pose = Isometry3::from_parts(
            Translation3::new(v[1], v[2], v[3]),
            UnitQuaternion::from_quaternion(Quaternion::new(v[7], v[4], v[5], v[6])),
        );
        let err = pose.inverse() * f.pose_wc;
        assert!(err.translation.vector.norm() < 1e-8 && err.rotation.angle() < 1e-8);
    }
    // Timestamps increase by 1/30 s.
    let t: Vec<f64> = assoc
        .iter()
        .map(|l| l.split(' ').next().unwrap().parse().unwrap())
        .collect();
    assert!(t
        .windows(2)
        .all(|p| ((p[1] - p[0]) - 1.0 / 30.0).abs() < 2e-6));
    // Refuses to overwrite.
    assert!(matches!(
        write_synthetic(&gen, 1, &dir, |_| {}),
        Err(DatasetError::OutputExists { .. })
    ));
    fs::remove_dir_all(&dir).unwrap();
}

fn yaml_list(text: &str, key: &str) -> Vec<f64> {
    let start = text.find(key).unwrap() + key.len();
    let rest = &text[start..];
    let open = rest.find('[').unwrap();
    let close = rest.find(']').unwrap();
    rest[open + 1..close]
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect()
}

#[test]
fn euroc_folder_reads_back_identically() {
    let gen = Generator::new(SynthConfig::preset("stereo").unwrap(), 4);
    let cam = gen.camera();
    let dir = temp_dir("euroc");
    let n = 3;
    write_synthetic(&gen, n, &dir, |_| {}).unwrap();
    let mav = dir.join("mav0");
    let csv0 = lines(&mav.join("cam0/data.csv"));
    assert_eq!(csv0[0], "#timestamp [ns],filename");
    assert_eq!(csv0, lines(&mav.join("cam1/data.csv")));
    let gt = lines(&mav.join("state_groundtruth_estimate0/data.csv"));
    assert_eq!(
        gt[0],
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []"
    );
    let y0 = fs::read_to_string(mav.join("cam0/sensor.yaml")).unwrap();
    let y1 = fs::read_to_string(mav.join("cam1/sensor.yaml")).unwrap();
    assert!(y0.starts_with("%YAML:1.0\n"));
    assert_eq!(
        yaml_list(&y0, "intrinsics:"),
        vec![cam.fx, cam.fy, cam.cx, cam.cy]
    );
    assert_eq!(
        yaml_list(&y0, "resolution:"),
        vec![cam.width as f64, cam.height as f64]
    );
    assert_eq!(yaml_list(&y0, "distortion_coefficients:"), vec![0.0; 4]);
    let t_bs = |y: &str| {
        let d = yaml_list(y, "data:");
        assert_eq!(d.len(), 16);
        let m = Matrix4::from_row_slice(&d);
        let r = nalgebra::Rotation3::from_matrix(&m.fixed_view::<3, 3>(0, 0).into_owned());
        Isometry3::from_parts(
            Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
            UnitQuaternion::from_rotation_matrix(&r),
        )
    };
    let (bs0, bs1) = (t_bs(&y0), t_bs(&y1));
    assert!(
        bs0.translation.vector.norm() > 0.01 && bs0.rotation.angle() > 1.0,
        "T_BS is not trivial"
    );
    // cam1 sits at the baseline along cam0's x axis.
    let c0c1 = bs0.inverse() * bs1;
    assert!(
        (c0c1.translation.vector - nalgebra::Vector3::new(cam.baseline(), 0.0, 0.0)).norm() < 1e-9
    );
    for i in 0..n {
        let f = gen.frame(i);
        let ns = gen.stamp_ns(i);
        assert_eq!(csv0[1 + i], format!("{ns},{ns}.png"));
        for (c, img) in [("cam0", &f.gray), ("cam1", f.right.as_ref().unwrap())] {
            let png = image::open(mav.join(format!("{c}/data/{ns}.png"))).unwrap();
            assert!(matches!(png, image::DynamicImage::ImageLuma8(_)));
            assert_eq!(png.to_luma8().into_raw(), img.data);
        }
        // Body pose composed with T_BS gives the exact camera pose.
        let parts: Vec<&str> = gt[1 + i].split(',').collect();
        assert_eq!(parts[0].parse::<u64>().unwrap(), ns);
        let v: Vec<f64> = parts[1..].iter().map(|x| x.parse().unwrap()).collect();
        let body = Isometry3::from_parts(
            Translation3::new(v[0], v[1], v[2]),
            UnitQuaternion::from_quaternion(Quaternion::new(v[3], v[4], v[5], v[6])),
        );
        let err = (body * bs0).inverse() * f.pose_wc;
        assert!(
            err.translation.vector.norm() < 1e-8 && err.rotation.angle() < 1e-8,
            "frame {i}"
        );
    }
    fs::remove_dir_all(&dir).unwrap();
}
