//! The fuzz targets of the library crates' readers: each writes its input where the reader
//! expects a file (in a scratch folder, under the file's usual name) and calls the reader as
//! noisefree does, then uses what it read the way the next step would (a vocabulary quantises
//! descriptors, a settings file builds its rectification), so that a value which parses but
//! breaks that step is found too. Seeds are real files (`seeds/`) and the files noisefree's
//! own writers produce.

use crate::engine::driver::{scratch_dir, Target};
use crate::fixup;
use ate_eval::io as traj;
use ate_eval::{AssociationMode, AteOptions, RpeDelta, StampPolicy};
use datasets::settings::{self, CameraSettings, SettingsFormat};
use nalgebra::Isometry3;
use slam_core::place::vocabulary::{NodeRecord, Vocabulary, Weighting};
use slam_core::{Camera, SensorKind};
use std::path::{Path, PathBuf};

/// Bytes of a seed file of `seeds/`.
macro_rules! seed {
    ($name:literal) => {
        include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/seeds/", $name)).to_vec()
    };
}

/// A reader of a file named `name` in this process's scratch folder.
fn on_file(
    name: &'static str,
    read: impl Fn(&Path) -> Result<(), String> + Send + Sync + 'static,
) -> crate::engine::driver::Reader {
    crate::engine::driver::on_file(scratch_dir("lib").join(name), read)
}

/// A target of the crate's readers: 16 bytes live per input byte at most.
fn target(
    name: &'static str,
    about: &'static str,
    file: &'static str,
    seeds: Vec<Vec<u8>>,
    dictionary: &[&str],
    read: crate::engine::driver::Reader,
) -> Target {
    Target::new(name, about, file, seeds, dictionary, 16.0, read)
}

fn e(err: impl std::fmt::Display) -> String {
    err.to_string()
}

/// The TUM trajectory seeds as KITTI poses (noisefree's writer).
fn kitti_seeds() -> Vec<Vec<u8>> {
    let dir = scratch_dir("seed");
    let p = dir.join("seed.txt");
    let mut out = Vec::new();
    for s in [seed!("tum-orbslam2.txt"), seed!("euroc-cam0.tum.txt")] {
        if std::fs::write(&p, &s).is_ok() {
            if let Ok(t) = traj::read_tum(&p) {
                out.push(traj::format_kitti(&t).into_bytes());
            }
        }
    }
    out
}

fn kitti_times_seed() -> Vec<u8> {
    (0..30)
        .map(|i| format!("{:.6e}\n", i as f64 * 0.1))
        .collect::<String>()
        .into_bytes()
}

/// Settings files of every layout noisefree writes: ORB-SLAM2 and ORB-SLAM3, RGB-D and
/// stereo (rectified, raw with the real EuRoC rig), at a small and the real size.
fn settings_seeds() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut small_stereo = Camera::euroc_rectified();
    (small_stereo.width, small_stereo.height) = (64, 40);
    let mut small_rgbd = Camera::tum_fr1();
    (small_rgbd.width, small_rgbd.height) = (64, 48);
    let mut cams = vec![
        CameraSettings::of_camera(&Camera::tum_fr1(), Some(5000.0), None),
        CameraSettings::of_camera(&small_rgbd, Some(5208.0), None),
        CameraSettings::of_camera(&small_stereo, None, None),
    ];
    // The real EuRoC rig (raw cameras and rectification) from the seeds' sensor.yaml files.
    let dir = scratch_dir("seed");
    let (l, r) = (dir.join("cam0.yaml"), dir.join("cam1.yaml"));
    if std::fs::write(&l, seed!("euroc-cam0-sensor.yaml")).is_ok()
        && std::fs::write(&r, seed!("euroc-cam1-sensor.yaml")).is_ok()
    {
        if let (Ok(mut a), Ok(mut b)) = (
            datasets::euroc::read_sensor_yaml(&l),
            datasets::euroc::read_sensor_yaml(&r),
        ) {
            // At a tenth of the size, so that building its rectification stays cheap.
            for c in [&mut a, &mut b] {
                (c.width, c.height) = (75, 48);
                (c.fx, c.fy, c.cx, c.cy) = (c.fx / 10.0, c.fy / 10.0, c.cx / 10.0, c.cy / 10.0);
            }
            if let Ok(rect) = datasets::rectify::StereoRectification::new(&a, &b) {
                cams.push(CameraSettings::of_camera(
                    &rect.camera(35.0),
                    None,
                    Some(&rect),
                ));
            }
        }
    }
    for c in &cams {
        for f in [SettingsFormat::Orbslam2, SettingsFormat::Orbslam3] {
            out.push(settings::write_settings(c, f, "fuzz seed").into_bytes());
        }
    }
    out
}

/// Small vocabularies in both forms: a complete k = 3, L = 3 tree and a ragged k = 4 one.
fn vocabularies() -> Vec<Vocabulary> {
    let mut out = Vec::new();
    for (k, levels, ragged) in [(3usize, 3usize, false), (4, 3, true)] {
        let mut nodes = Vec::new();
        let mut frontier = vec![0u32];
        let mut next_id = 1u32;
        for depth in 1..=levels {
            let mut next = Vec::new();
            for &p in &frontier {
                let n = if ragged {
                    2 + (p as usize % (k - 1))
                } else {
                    k
                };
                for c in 0..n {
                    let leaf = depth == levels || (ragged && c == 0 && depth > 1);
                    let id = next_id;
                    next_id += 1;
                    let byte = (id as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                    nodes.push(NodeRecord {
                        parent: p,
                        is_leaf: leaf,
                        descriptor: [byte, byte.rotate_left(13), byte ^ 0xffff, !byte],
                        weight: if leaf {
                            0.5 + (id % 7) as f64 * 0.25
                        } else {
                            0.0
                        },
                    });
                    if !leaf {
                        next.push(id);
                    }
                }
            }
            frontier = next;
        }
        if let Ok(v) = Vocabulary::from_nodes(k, levels, Weighting::TfIdf, &nodes) {
            out.push(v);
        }
    }
    out
}

/// What every trajectory a reader accepts must be (else the target panics, a finding):
/// stamps finite and in time order, poses finite with unit rotations.
fn check_trajectory(t: &ate_eval::Trajectory) {
    assert_eq!(t.stamps.len(), t.poses.len());
    assert!(
        t.stamps.iter().all(|s| s.is_finite()),
        "a stamp is not finite"
    );
    assert!(
        t.stamps.windows(2).all(|w| w[0] <= w[1]),
        "stamps out of order"
    );
    for p in &t.poses {
        assert!(p.translation.vector.iter().all(|v| v.is_finite()), "{p:?}");
        assert!((p.rotation.norm() - 1.0).abs() < 1e-9, "{p:?}");
    }
}

/// A TUM trajectory of `n` poses `step` seconds apart: with `n * step` under the 20 ms window
/// of evaluate_ate.py, every stamp is a candidate partner of every other (a system writing
/// nanosecond stamps, or at a wrong rate), the worst case of the greedy pairing.
fn crowded_trajectory(n: usize, step: f64) -> Vec<u8> {
    (0..n)
        .map(|k| {
            let a = k as f64 * 0.01;
            format!(
                "{:.6} {:.4} {:.4} {:.4} 0 0 0 1\n",
                1_305_031_102.0 + k as f64 * step,
                a.cos(),
                a.sin(),
                0.001 * k as f64
            )
        })
        .collect::<String>()
        .into_bytes()
}

/// What `noisefree eval` does with a trajectory file, with the file as both ground truth and
/// estimate: read under each association's stamp policy, paired (at offsets 0 and 13 ms, so
/// that the greedy pairing has choices to make), scored (ATE, RPE over a frame and over
/// 50 ms). Errors of the evaluation are given the file as `eval` gives them; an accepted
/// evaluation must pair each stamp at most once, within the window, with finite errors.
fn evaluate(p: &Path) -> Result<(), String> {
    let fail = |err: ate_eval::Error| format!("evaluating {} against itself: {err}", p.display());
    let mut last = Ok(());
    for mode in [AssociationMode::Tum, AssociationMode::Evo] {
        let t = traj::read_tum_loaded(p, StampPolicy::for_association(mode))
            .map_err(e)?
            .trajectory;
        for offset in [0.0, 0.013] {
            let opts = AteOptions {
                offset,
                association: mode,
                ..AteOptions::default()
            };
            match ate_eval::evaluate_ate(&t, &t, &opts) {
                Ok(ate) => {
                    let mut used = (vec![false; t.len()], vec![false; t.len()]);
                    for &(i, j) in &ate.pairs {
                        let dt = (t.stamps[i] - (t.stamps[j] + offset)).abs();
                        assert!(dt <= opts.max_difference, "pair {i} {j}: |dt| = {dt}");
                        if mode == AssociationMode::Tum {
                            assert!(!used.0[i] && !used.1[j], "a stamp paired twice");
                            (used.0[i], used.1[j]) = (true, true);
                        }
                    }
                    assert!(ate.errors.iter().all(|x| x.is_finite()), "{:?}", ate.stats);
                }
                Err(err) => last = Err(fail(err)),
            }
            for delta in [RpeDelta::Frames(1), RpeDelta::Seconds(0.05)] {
                match ate_eval::evaluate_rpe(&t, &t, delta, &opts) {
                    Ok(r) => assert!(r.trans_errors.iter().all(|x| x.is_finite())),
                    Err(err) => last = Err(fail(err)),
                }
            }
        }
    }
    last
}

/// What every settings file a reader accepts must give: the ranges noisefree can run with.
fn check_settings(s: &CameraSettings) {
    let c = &s.camera;
    assert!(c.fx > 0.0 && c.fy > 0.0 && c.fx.is_finite() && c.fy.is_finite());
    assert!(c.width <= settings::MAX_IMAGE_SIDE && c.height <= settings::MAX_IMAGE_SIDE);
    assert!(s.orb.scale_factor > 1.0 && s.orb.scale_factor <= 4.0);
    assert!((1..=32).contains(&s.orb.n_levels) && s.orb.n_features >= 1);
    assert!(s.depth_factor.is_none_or(|f| f > 0.0 && f.is_finite()));
}

/// Uses a vocabulary read from an input as place recognition does: quantises descriptors.
fn use_vocabulary(v: &Vocabulary) {
    let descriptors: Vec<_> = (0..8u64)
        .map(|i| {
            let x = i.wrapping_mul(0x2545_f491_4f6c_dd1d);
            [x, !x, x.rotate_left(7), x ^ 0x5555]
        })
        .collect();
    let _ = v.transform(&descriptors, 4);
}

/// Small images of every pixel format the readers meet (grey, grey+alpha, RGB, RGBA; 8 and 16
/// bit), cut from a real EuRoC frame when it is at hand, else a rendered gradient.
fn image_seeds(format: image::ImageFormat) -> Vec<Vec<u8>> {
    let (w, h) = (24u32, 16u32);
    let grey: Vec<u8> = (0..w * h)
        .map(|i| ((i % w) * 9 + (i / w) * 5) as u8)
        .collect();
    let mut out = Vec::new();
    let mut push = |img: image::DynamicImage| {
        let mut buf = std::io::Cursor::new(Vec::new());
        if img.write_to(&mut buf, format).is_ok() {
            out.push(buf.into_inner());
        }
    };
    let luma = image::GrayImage::from_raw(w, h, grey.clone()).map(image::DynamicImage::ImageLuma8);
    if let Some(l) = luma {
        push(l.clone());
        push(image::DynamicImage::ImageRgb8(l.to_rgb8()));
        if format == image::ImageFormat::Png {
            push(image::DynamicImage::ImageRgba8(l.to_rgba8()));
            push(image::DynamicImage::ImageLumaA8(l.to_luma_alpha8()));
            push(image::DynamicImage::ImageLuma16(l.to_luma16()));
            push(image::DynamicImage::ImageRgb16(l.to_rgb16()));
            let mut tiny = l.clone();
            tiny = tiny.crop_imm(0, 0, 1, 1);
            push(tiny);
        }
    }
    out
}

/// The PNG seeds of `seeds/` in the formats the `image` crate's encoder does not write
/// (palettes, 1/2/4-bit grey, a transparency key, grey+alpha and RGB(A) at 16 bits, Adam7,
/// files cut short), written by [`crate::png::seeds`] (test `image_seeds`).
fn written_png_seeds() -> Vec<Vec<u8>> {
    vec![
        seed!("png-grey1.png"),
        seed!("png-grey2-adam7.png"),
        seed!("png-grey4.png"),
        seed!("png-grey4-adam7-3x1.png"),
        seed!("png-grey8-trns.png"),
        seed!("png-greyalpha8.png"),
        seed!("png-greyalpha16-adam7.png"),
        seed!("png-rgb16.png"),
        seed!("png-rgba16-adam7.png"),
        seed!("png-depth16-adam7.png"),
        seed!("png-palette1.png"),
        seed!("png-palette2-adam7.png"),
        seed!("png-palette4-trns.png"),
        seed!("png-palette8.png"),
        seed!("png-palette4-past-the-end.png"),
        seed!("png-depth16-cut-in-idat.png"),
        seed!("png-rgb8-no-iend.png"),
    ]
}

/// Every target of the library crates' readers.
pub fn all() -> Vec<Target> {
    let tum_list_words = ["rgb/", ".png", "depth/", "# timestamp filename"];
    let traj_words = ["# timestamp tx ty tz qx qy qz qw", "1311868229.5494"];
    let yaml_words = [
        "%YAML:1.0",
        "T_BS:",
        "data:",
        "rows:",
        "cols:",
        "resolution:",
        "intrinsics:",
        "distortion_coefficients:",
        "rate_hz:",
        "camera_model:",
        "distortion_model:",
        "pinhole",
        "radial-tangential",
    ];
    let settings_words = [
        "Camera.fx:",
        "Camera.width:",
        "Camera.height:",
        "Camera.bf:",
        "ThDepth:",
        "DepthMapFactor:",
        "ORBextractor.scaleFactor:",
        "ORBextractor.nLevels:",
        "ORBextractor.nFeatures:",
        "ORBextractor.iniThFAST:",
        "File.version:",
        "Camera.type:",
        "\"PinHole\"",
        "\"Rectified\"",
        "Stereo.b:",
        "Stereo.T_c1_c2:",
        "LEFT.K:",
        "RIGHT.R:",
        "LEFT.P:",
        "!!opencv-matrix",
        "rows: 3",
        "cols: 3",
        "rows: 4000000000",
        "data: [",
    ];
    let mut out = vec![
        target(
            "tum-list",
            "TUM RGB-D rgb.txt / depth.txt (datasets::tum::read_list)",
            "rgb.txt",
            vec![seed!("tum-rgb.txt"), seed!("tum-depth.txt")],
            &tum_list_words,
            on_file("rgb.txt", |p| {
                let list = datasets::tum::read_list(p).map_err(e)?;
                assert!(list.iter().all(|l| l.stamp.is_finite() && !l.file.is_empty()));
                assert!(list.windows(2).all(|w| w[0].stamp <= w[1].stamp));
                Ok(())
            }),
        ),
        {
            // The folder's pairing (datasets::tum::pairs): the input is both rgb.txt and
            // depth.txt, so that dense or repeated stamps meet themselves.
            let dir = scratch_dir("lib").join("tum-folder");
            let _ = std::fs::create_dir_all(&dir);
            target(
                "tum-pairs",
                "a TUM folder's rgb.txt / depth.txt association (datasets::tum::pairs)",
                "rgb.txt",
                vec![seed!("tum-rgb.txt"), seed!("tum-depth.txt")],
                &tum_list_words,
                Box::new(move |b: &[u8]| {
                    for name in ["rgb.txt", "depth.txt"] {
                        let p = dir.join(name);
                        std::fs::write(&p, b).map_err(|err| format!("{}: {err}", p.display()))?;
                    }
                    datasets::tum::pairs(&dir, datasets::tum::MAX_DIFFERENCE)
                        .map(|_| ())
                        .map_err(e)
                }),
            )
        },
        target(
            "tum-associations",
            "ORB-SLAM2 associations.txt (datasets::tum::read_associations)",
            "associations.txt",
            vec![seed!("tum-associations.txt")],
            &tum_list_words,
            on_file("associations.txt", |p| {
                datasets::tum::read_associations(p).map(|_| ()).map_err(e)
            }),
        ),
        target(
            "tum-trajectory",
            "TUM trajectories (ate_eval::io::read_tum_loaded, every stamp policy)",
            "trajectory.txt",
            vec![
                seed!("tum-groundtruth.txt"),
                seed!("tum-groundtruth-repeat.txt"),
                seed!("tum-orbslam2.txt"),
                seed!("euroc-cam0.tum.txt"),
            ],
            &traj_words,
            on_file("trajectory.txt", |p| {
                for policy in [StampPolicy::LastWins, StampPolicy::KeepAll] {
                    check_trajectory(&traj::read_tum_loaded(p, policy).map_err(e)?.trajectory);
                }
                traj::read_tum_loaded(p, StampPolicy::Strict)
                    .map(|l| check_trajectory(&l.trajectory))
                    .map_err(e)
            }),
        ),
        target(
            "eval",
            "`noisefree eval`'s pairing and scoring of a TUM trajectory against itself (ate_eval: evaluate_ate.py's greedy and evo's nearest association, offsets 0 and 13 ms, ATE and RPE)",
            "trajectory.txt",
            vec![
                seed!("tum-groundtruth.txt"),
                seed!("tum-orbslam2.txt"),
                seed!("euroc-cam0.tum.txt"),
                crowded_trajectory(2000, 5e-6),
                crowded_trajectory(300, 1e-4),
            ],
            &traj_words,
            on_file("trajectory.txt", evaluate),
        ),
        target(
            "euroc-groundtruth",
            "EuRoC ground-truth CSV (ate_eval::io::read_euroc_loaded)",
            "data.csv",
            vec![seed!("euroc-groundtruth.csv")],
            &["#timestamp [ns]", "1403715274312143104"],
            on_file("data.csv", |p| {
                traj::read_euroc_loaded(p, StampPolicy::LastWins)
                    .map(|l| check_trajectory(&l.trajectory))
                    .map_err(e)
            }),
        ),
        target(
            "kitti-poses",
            "KITTI poses (ate_eval::io::read_kitti_loaded)",
            "poses.txt",
            kitti_seeds(),
            &["1.000000000e0", "0.000000000e0"],
            on_file("poses.txt", |p| {
                traj::read_kitti_loaded(p, None, StampPolicy::LastWins)
                    .map(|l| check_trajectory(&l.trajectory))
                    .map_err(e)
            }),
        ),
        {
            // KITTI times.txt beside a fixed, valid pose file of as many lines.
            let dir = scratch_dir("lib");
            let poses = dir.join("kitti-poses-for-times.txt");
            let first = kitti_seeds().into_iter().next().unwrap_or_default();
            let _ = std::fs::write(&poses, first);
            target(
                "kitti-times",
                "KITTI times.txt (ate_eval::io::read_kitti_loaded with times)",
                "times.txt",
                vec![kitti_times_seed()],
                &[],
                on_file("times.txt", move |p| {
                    traj::read_kitti_loaded(&poses, Some(p), StampPolicy::KeepAll)
                        .map(|l| check_trajectory(&l.trajectory))
                        .map_err(e)
                }),
            )
        },
        target(
            "euroc-camera-csv",
            "EuRoC cam0/cam1 data.csv (datasets::euroc::read_camera_csv)",
            "data.csv",
            vec![seed!("euroc-cam0-data.csv")],
            &["#timestamp [ns],filename", ".png"],
            on_file("data.csv", |p| {
                datasets::euroc::read_camera_csv(p).map(|_| ()).map_err(e)
            }),
        ),
        {
            let right = scratch_dir("lib").join("right-sensor.yaml");
            let _ = std::fs::write(&right, seed!("euroc-cam1-sensor.yaml"));
            target(
                "euroc-sensor-yaml",
                "EuRoC sensor.yaml (datasets::euroc::read_sensor_yaml, ate_eval's T_BS reader, the rectification)",
                "sensor.yaml",
                vec![
                    seed!("euroc-cam0-sensor.yaml"),
                    seed!("euroc-cam1-sensor.yaml"),
                    seed!("euroc-imu0-sensor.yaml"),
                ],
                &yaml_words,
                on_file("sensor.yaml", move |p| {
                    let t = traj::read_euroc_t_bs(p);
                    let left = datasets::euroc::read_sensor_yaml(p).map_err(e)?;
                    assert!(left.fx > 0.0 && left.fy > 0.0 && left.rate_hz > 0.0);
                    assert!((1..=settings::MAX_IMAGE_SIDE).contains(&left.width));
                    assert!((1..=settings::MAX_IMAGE_SIDE).contains(&left.height));
                    t.map_err(e)?;
                    let mut r = datasets::euroc::read_sensor_yaml(&right).map_err(e)?;
                    (r.width, r.height) = (left.width, left.height);
                    // The rectification's maps cost a pass over the image: small sizes only.
                    if u64::from(left.width) * u64::from(left.height) <= 100 * 100 {
                        datasets::rectify::StereoRectification::new(&left, &r)
                            .map_err(|err| format!("{}: {err}", p.display()))?;
                    }
                    Ok(())
                }),
            )
        },
        target(
            "settings-yaml",
            "ORB-SLAM2 / ORB-SLAM3 settings YAML (datasets::settings::read_settings, RGB-D and stereo, and the rectification it gives)",
            "settings.yaml",
            settings_seeds(),
            &settings_words,
            on_file("settings.yaml", |p| {
                let mut last = Ok(());
                for sensor in [SensorKind::Rgbd, SensorKind::Stereo] {
                    match settings::read_settings(p, sensor) {
                        Ok(s) => {
                            check_settings(&s);
                            let c = &s.camera;
                            if u64::from(c.width) * u64::from(c.height) <= 200 * 200
                                && sensor == SensorKind::Stereo
                            {
                                s.rectification(p, Isometry3::identity()).map_err(e)?;
                            }
                        }
                        Err(err) => last = Err(e(err)),
                    }
                }
                last
            }),
        ),
        {
            let seeds = vocabularies()
                .iter()
                .map(|v| v.to_text().into_bytes())
                .collect();
            target(
                "vocab-text",
                "DBoW2 text vocabulary, ORBvoc.txt's form (slam_core Vocabulary::from_bytes), then quantising",
                "",
                seeds,
                &["10 6 0 0", "0 1", "1 0"],
                Box::new(|b: &[u8]| {
                    let v = Vocabulary::from_bytes(b).map_err(e)?;
                    use_vocabulary(&v);
                    Ok(())
                }),
            )
        },
        {
            let seeds = vocabularies().iter().map(|v| v.to_binary()).collect();
            let mut t = target(
                "vocab-binary",
                "noisefree binary vocabulary (slam_core Vocabulary::from_bytes, checksum repaired after mutation), then quantising",
                "",
                seeds,
                &["NFVOCAB1"],
                Box::new(|b: &[u8]| {
                    let v = Vocabulary::from_bytes(b).map_err(e)?;
                    use_vocabulary(&v);
                    Ok(())
                }),
            );
            t.fixup = Some(fixup::vocabulary_checksum);
            t
        },
        {
            let mut seeds = image_seeds(image::ImageFormat::Png);
            seeds.extend(written_png_seeds());
            let mut t = target(
                "png-gray",
                "PNG images, any pixel format, to 8-bit grey (datasets::decode::read_gray)",
                "image.png",
                seeds,
                &["IHDR", "IDAT", "IEND", "PLTE", "tRNS"],
                on_file("image.png", |p| {
                    datasets::decode::read_gray(p).map(|_| ()).map_err(e)
                }),
            );
            t.fixup = Some(fixup::png_crcs);
            t.alloc_factor = IMAGE_ALLOC_FACTOR;
            t
        },
        {
            let mut seeds = image_seeds(image::ImageFormat::Png);
            seeds.extend(written_png_seeds());
            let mut t = target(
                "png-depth",
                "16-bit depth PNG to metres (datasets::decode::read_depth)",
                "depth.png",
                seeds,
                &["IHDR", "IDAT", "IEND"],
                on_file("depth.png", |p| {
                    datasets::decode::read_depth(p, 5000.0)
                        .map(|_| ())
                        .map_err(e)
                }),
            );
            t.fixup = Some(fixup::png_crcs);
            t.alloc_factor = IMAGE_ALLOC_FACTOR;
            t
        },
        {
            let mut seeds = image_seeds(image::ImageFormat::Jpeg);
            seeds.extend(image_seeds(image::ImageFormat::Png));
            seeds.extend(written_png_seeds());
            let mut t = target(
                "image-any",
                "PNG or JPEG of `noisefree features` (datasets::decode::read_image)",
                "image.jpg",
                seeds,
                &[],
                on_file("image.jpg", |p| {
                    datasets::decode::read_image(p).map(|_| ()).map_err(e)
                }),
            );
            t.fixup = Some(fixup::png_crcs_if_png);
            t.alloc_factor = IMAGE_ALLOC_FACTOR;
            t
        },
    ];
    out.sort_by_key(|t| t.name);
    out
}

/// Bytes an image reader may hold per input byte: a file decodes to at most
/// [`datasets::decode::MAX_DECODED_BYTES_PER_BYTE`] bytes of pixels a byte (deflate's 1032:1,
/// a 1-bit sample to a byte), held at once with its conversion (16-bit depth to f32: 3 times
/// the decoded bytes; colour to grey: less).
pub const IMAGE_ALLOC_FACTOR: f64 = datasets::decode::MAX_DECODED_BYTES_PER_BYTE as f64 * 3.0;

/// Where the targets write their inputs (for the report).
pub fn scratch() -> PathBuf {
    scratch_dir("lib")
}

/// Removes the scratch folders of this process (the inputs' and the seeds').
pub fn remove_scratch() {
    for name in ["lib", "seed"] {
        let _ = std::fs::remove_dir_all(scratch_dir(name));
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_image_targets_start_from_every_written_png_seed() {
        let written: Vec<Vec<u8>> = crate::png::seeds().into_iter().map(|s| s.bytes).collect();
        assert_eq!(super::written_png_seeds(), written);
    }
}
