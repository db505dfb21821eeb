//! The colour camera's imaging effects against their definitions: blur length equals the
//! image motion over the exposure, rolling-shutter rows at their own instants, lens
//! distortion undone by the readers' undistortion, auto-exposure reaching its target, and
//! random access unchanged by the auto-exposure's history.

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use slam_core::Camera;
use synth::sensor::imaging::{AutoExposure, Exposure, RollingShutter, SensorNoise, Vignetting};
use synth::sensor::render::{Exposed, Shading, View};
use synth::world::layout::{ROOM_HALF, ROOM_HEIGHT};
use synth::world::scene::Scene;
use synth::world::texture::Texture;
use synth::{Generator, Supersampling, SynthConfig};

const DARK: u8 = 40;
const BRIGHT: u8 = 220;

/// An empty room, flat grey, whose +y wall is dark for x < 0 and bright for x >= 0: one
/// vertical step edge straight ahead of a camera at the origin looking along +y.
fn edge_room() -> Scene {
    let flat = |w: f64, h: f64| Texture::from_fn(w, h, 1.0, |_, _| [128; 3]);
    let side = 2.0 * ROOM_HALF;
    let mut textures = vec![
        flat(side, side),
        flat(side, side),
        flat(side, ROOM_HEIGHT),
        flat(side, ROOM_HEIGHT),
        flat(side, ROOM_HEIGHT),
    ];
    // +y wall: s = x + ROOM_HALF.
    textures.push(Texture::from_fn(side, ROOM_HEIGHT, 400.0, |s, _| {
        if s < ROOM_HALF {
            [DARK; 3]
        } else {
            [BRIGHT; 3]
        }
    }));
    Scene {
        objects: Vec::new(),
        textures,
        light: Vector3::new(0.0, 0.0, 2.6),
        people: Vec::new(),
        room: synth::world::layout::RoomBox {
            half: [ROOM_HALF; 2],
            height: ROOM_HEIGHT,
        },
    }
}

/// Camera at (0, 0, 1.35) looking along +y, turned by `yaw` about the vertical.
fn looking_at_wall(yaw: f64) -> Isometry3<f64> {
    let r0 = Rotation3::from_basis_unchecked(&[Vector3::x(), -Vector3::z(), Vector3::y()]);
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw) * r0;
    Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 1.35),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

/// Flat shading: the rendered level is the texture's.
fn flat() -> Shading {
    Shading {
        supersampling: Supersampling::None,
        ambient: 1.0,
    }
}

/// Sub-pixel column where row `v`'s grey profile crosses `level` (first crossing).
fn crossing(img: &[[f32; 3]], w: usize, v: usize, level: f32) -> f64 {
    let row = &img[v * w..(v + 1) * w];
    for u in 0..w - 1 {
        let (a, b) = (row[u][1], row[u + 1][1]);
        if (a - level) * (b - level) <= 0.0 && a != b {
            return u as f64 + ((level - a) / (b - a)) as f64;
        }
    }
    panic!("row {v} never crosses {level}");
}

/// 10-90 % width of the edge in row `v`, scaled to the full width of a linear ramp.
fn ramp_width(img: &[[f32; 3]], w: usize, v: usize) -> f64 {
    let span = (BRIGHT - DARK) as f32;
    let lo = crossing(img, w, v, DARK as f32 + 0.1 * span);
    let hi = crossing(img, w, v, DARK as f32 + 0.9 * span);
    (hi - lo).abs() / 0.8
}

const OMEGA: f64 = 0.5; // rad/s about the vertical

fn exposed(scene: &Scene, cam: &Camera, exposure_s: f64, readout_s: f64) -> Vec<[f32; 3]> {
    let pose_at = |t: f64| looking_at_wall(OMEGA * t);
    Exposed {
        scene,
        camera: cam,
        pose_at: &pose_at,
        occluded: false,
        time: 0.0,
        exposure_s,
        readout_s,
        samples: 32,
        shading: flat(),
    }
    .render()
}

#[test]
fn blur_length_equals_image_motion_over_the_exposure() {
    let scene = edge_room();
    let cam = Camera::tum_fr3();
    let w = cam.width as usize;
    let sharp = exposed(&scene, &cam, 0.0, 0.0);
    let e = 0.03;
    let blurred = exposed(&scene, &cam, e, 0.0);
    // The edge straight ahead sweeps fx * tan(omega * e) pixels during the exposure.
    let motion = cam.fx * (OMEGA * e / 2.0).tan() * 2.0;
    let (ws, wb) = (ramp_width(&sharp, w, 240), ramp_width(&blurred, w, 240));
    assert!(ws < 2.0, "a snapshot's edge is about a pixel wide: {ws}");
    assert!(
        (wb - motion).abs() < 1.0,
        "blur {wb:.2} px, image motion {motion:.2} px"
    );
    // The blurred edge is centred where the snapshot's is (the stamp is mid-exposure).
    let mid = (DARK as f32 + BRIGHT as f32) / 2.0;
    assert!((crossing(&sharp, w, 240, mid) - crossing(&blurred, w, 240, mid)).abs() < 0.3);
    assert!((crossing(&sharp, w, 240, mid) - cam.cx).abs() < 0.3);
}

#[test]
fn rolling_shutter_rows_are_exposed_at_their_own_instants() {
    let scene = edge_room();
    let cam = Camera::tum_fr3();
    let (w, h) = (cam.width as usize, cam.height as usize);
    let readout = 0.03;
    let img = exposed(&scene, &cam, 0.0, readout);
    let mid = (DARK as f32 + BRIGHT as f32) / 2.0;
    // Row v is taken at readout * ((v + 0.5) / h - 0.5) after the stamp, when the camera has
    // turned by omega times that; the wall point x = 0 straight ahead at the stamp then lies at
    // u = cx - fx tan(angle) in that row (yaw to the left moves the scene to the right).
    for v in [20usize, 120, 240, 360, 460] {
        let t = synth::sensor::imaging::row_time(v as f64, h, readout);
        let expected = cam.cx + cam.fx * (OMEGA * t).tan() * sign_of_yaw(&cam);
        let got = crossing(&img, w, v, mid);
        assert!(
            (got - expected).abs() < 0.3,
            "row {v}: edge at {got:.2}, expected {expected:.2}"
        );
    }
    // And a global shutter does not slant it.
    let global = exposed(&scene, &cam, 0.0, 0.0);
    assert!((crossing(&global, w, 20, mid) - crossing(&global, w, 460, mid)).abs() < 0.2);
}

/// +1 when turning by a positive yaw moves the scene towards larger u, else -1, measured on the
/// projection of the point straight ahead.
fn sign_of_yaw(cam: &Camera) -> f64 {
    let p = Vector3::new(0.0, ROOM_HALF, 1.35);
    let q = looking_at_wall(0.01).inverse() * nalgebra::Point3::from(p);
    let u = cam.fx * q.x / q.z + cam.cx;
    (u - cam.cx).signum()
}

#[test]
fn undistorting_the_written_image_recovers_the_pinhole_rendering() {
    let scene = Scene::new(3, None);
    let placed = scene.place(0.0);
    let pose = synth::motion::trajectory::pose_at(&synth::Trajectory::Xyz, 1.0);
    let distorted_cam = Camera::tum_fr1();
    let pinhole_cam = Camera {
        distortion: None,
        ..Camera::tum_fr1()
    };
    let render = |cam: &Camera| {
        View {
            scene: &scene,
            placed: &placed,
            camera: cam,
            pose_wc: pose,
            occluded: false,
        }
        .render(None)
        .depth
    };
    let (dd, dp) = (render(&distorted_cam), render(&pinhole_cam));
    let (w, h) = (640usize, 480usize);
    let bilinear = |u: f64, v: f64| -> Option<f64> {
        let (x0, y0) = (u.floor() as i64, v.floor() as i64);
        if x0 < 0 || y0 < 0 || x0 + 1 >= w as i64 || y0 + 1 >= h as i64 {
            return None;
        }
        let (x0, y0) = (x0 as usize, y0 as usize);
        let q = [
            dp[y0 * w + x0],
            dp[y0 * w + x0 + 1],
            dp[(y0 + 1) * w + x0],
            dp[(y0 + 1) * w + x0 + 1],
        ];
        let (lo, hi) = q
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        if hi > lo * 1.01 {
            return None; // a depth edge: not comparable
        }
        let (fx, fy) = (u - x0 as f64, v - y0 as f64);
        let top = q[0] as f64 * (1.0 - fx) + q[1] as f64 * fx;
        let bot = q[2] as f64 * (1.0 - fx) + q[3] as f64 * fx;
        Some(top * (1.0 - fy) + bot * fy)
    };
    let (mut with, mut without) = (Vec::new(), Vec::new());
    for v in (5..h - 5).step_by(7) {
        for u in (5..w - 5).step_by(7) {
            let (uu, vu) = distorted_cam.undistort_point(u as f64, v as f64);
            if (uu - u as f64).hypot(vu - v as f64) < 3.0 {
                continue; // only where the lens moves the pixel
            }
            let z = dd[v * w + u] as f64;
            if let (Some(a), Some(b)) = (bilinear(uu, vu), bilinear(u as f64, v as f64)) {
                with.push((z - a).abs() / z);
                without.push((z - b).abs() / z);
            }
        }
    }
    assert!(with.len() > 500, "{} comparable pixels", with.len());
    let median = |x: &mut Vec<f64>| {
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    };
    let (mw, mo) = (median(&mut with), median(&mut without));
    assert!(mw < 2e-4, "undistorted lookup: median relative error {mw}");
    assert!(mo > 10.0 * mw, "the lens must move pixels: {mo} vs {mw}");
}

fn with_imaging(f: impl FnOnce(&mut SynthConfig)) -> SynthConfig {
    let mut c = SynthConfig::preset("kinect").unwrap();
    c.camera.width = 320;
    c.camera.height = 240;
    c.camera.cx = 160.0;
    c.camera.cy = 120.0;
    c.camera.fx /= 2.0;
    c.camera.fy /= 2.0;
    f(&mut c);
    c
}

fn mean_grey(g: &Generator, i: usize) -> f64 {
    let f = g.frame(i);
    f.gray.data.iter().map(|&x| x as f64).sum::<f64>() / f.gray.data.len() as f64
}

#[test]
fn auto_exposure_brings_a_dark_scene_to_its_target_with_gain() {
    // The exposure time may not grow beyond the nominal 5 ms: the gain must make up the rest.
    let ae = AutoExposure {
        target: 160.0,
        rate: 0.3,
        step_ev: 1.0 / 8.0,
        max_time_s: 0.005,
        max_gain: 16.0,
        history: 20,
    };
    let dark = with_imaging(|c| {
        c.image.ambient = 0.1;
        c.imaging.exposure = Some(Exposure {
            time_s: 0.005,
            samples: 2,
        });
        c.imaging.auto_exposure = Some(ae.clone());
        c.imaging.sensor_noise = Some(SensorNoise {
            read_dn: 1.0,
            electrons_per_dn: 20.0,
        });
    });
    let g = Generator::try_new(dark.clone(), 1).unwrap();
    let m = mean_grey(&g, 10);
    assert!((m - 160.0).abs() < 20.0, "mean grey {m}");
    let s = g.exposure_settings(10);
    assert!(s.time_s <= 0.005 + 1e-12 && s.gain > 1.2, "{s:?}");
    // Without auto-exposure the same scene is much darker.
    let mut off = dark;
    off.imaging.auto_exposure = None;
    let m_off = mean_grey(&Generator::try_new(off, 1).unwrap(), 10);
    assert!(m_off < 0.8 * m, "{m_off} vs {m}");
}

#[test]
fn a_frame_is_the_same_alone_or_after_its_predecessors() {
    let c = with_imaging(|c| {
        c.imaging.exposure = Some(Exposure {
            time_s: 0.01,
            samples: 3,
        });
        c.imaging.rolling_shutter = Some(RollingShutter { readout_s: 0.02 });
        c.imaging.vignetting = Some(Vignetting { corner: 0.7 });
        c.imaging.auto_exposure = Some(AutoExposure {
            target: 110.0,
            rate: 0.3,
            step_ev: 0.125,
            max_time_s: 0.03,
            max_gain: 8.0,
            history: 6,
        });
        c.imaging.sensor_noise = Some(SensorNoise {
            read_dn: 1.5,
            electrons_per_dn: 20.0,
        });
    });
    let seq = Generator::try_new(c.clone(), 4).unwrap();
    let in_order: Vec<_> = seq.frames(9).collect();
    let alone = Generator::try_new(c, 4).unwrap().frame(8);
    assert_eq!(in_order[8].gray.data, alone.gray.data);
    assert_eq!(in_order[8].rgb, alone.rgb);
}

#[test]
fn vignetting_darkens_the_corners_of_a_frame() {
    let c = with_imaging(|c| {
        c.image.noise_sigma = 0.0;
        c.imaging.vignetting = Some(Vignetting { corner: 0.5 });
    });
    let mut plain = c.clone();
    plain.imaging.vignetting = None;
    let (a, b) = (
        Generator::new(c, 2).frame(3),
        Generator::new(plain, 2).frame(3),
    );
    let w = 320;
    let ratio = |x: usize, y: usize| {
        let (mut s, mut t) = (0.0, 0.0);
        for v in y..y + 8 {
            for u in x..x + 8 {
                s += a.gray.data[v * w + u] as f64;
                t += b.gray.data[v * w + u] as f64;
            }
        }
        s / t
    };
    assert!((ratio(156, 116) - 1.0).abs() < 0.02, "{}", ratio(156, 116));
    assert!((ratio(0, 0) - 0.52).abs() < 0.05, "{}", ratio(0, 0));
}
