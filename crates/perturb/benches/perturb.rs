//! What one perturbation costs per frame (640x480 RGB-D, 752x480 stereo, one thread), beside
//! the ~5 ms of ORB extraction and ~6 ms of tracking a frame costs: each family on a textured
//! frame with a depth image of two planes (so the lateral, hole and edge models meet a
//! boundary).

use criterion::{criterion_group, criterion_main, Criterion};
use perturb::{Chain, Domain, Family, Perturber};
use slam_core::{Camera, DepthImage, FrameInput, GrayImage, SensorKind};
use std::sync::Arc;

fn frame(w: usize, h: usize, stereo: bool) -> FrameInput {
    let grey: Vec<u8> = (0..w * h)
        .map(|i| (((i % w) / 7 * 37 + (i / w) / 5 * 91) % 251) as u8)
        .collect();
    let img = Arc::new(GrayImage {
        width: w,
        height: h,
        data: grey,
    });
    FrameInput {
        timestamp: 0.0,
        image: img.clone(),
        depth: (!stereo).then(|| {
            Arc::new(DepthImage {
                width: w,
                height: h,
                data: (0..w * h)
                    .map(|i| if i % w < w / 2 { 1.2 } else { 3.0 })
                    .collect(),
            })
        }),
        right: stereo.then_some(img),
        colour: None,
    }
}

fn level(f: Family) -> f64 {
    match f {
        Family::DepthAxial => 4.0,
        Family::DepthLateral => 4.0,
        Family::DepthHoles => 20.0,
        Family::DepthEdges => 3.0,
        Family::DepthScale => 5.0,
        Family::DepthLag => 2.0,
        Family::ImageNoise => 8.0,
        Family::MotionBlur => 10.0,
        Family::Exposure => 10.0,
        Family::Jpeg => 50.0,
        Family::FrameDrop => 2.0,
        Family::StampJitter => 5.0,
        Family::RgbDepthOffset => 66.0,
        Family::Occluders => 3.0,
        Family::StereoMisalignment => 0.2,
        Family::DepthDistortion => 1.5,
        Family::DepthRegistration => 2.0,
        Family::IrShadow => 1.0,
        Family::DisparityQuantization => 1.0,
        // Not per frame: the given camera and the scored ground truth (not benched).
        Family::FocalError
        | Family::PrincipalPointError
        | Family::DistortionError
        | Family::GtOffset
        | Family::GtJitter
        | Family::GtHandEye => 0.0,
    }
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("perturbation per frame");
    group.sample_size(20);
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .ok();
    for f in Family::ALL {
        if matches!(f.domain(), Domain::Calibration | Domain::GroundTruth) {
            continue;
        }
        let stereo = f == Family::StereoMisalignment || !f.applies_to(SensorKind::Rgbd);
        let mut camera = if stereo {
            let mut c = Camera::tum_fr3();
            c.width = 752;
            c.sensor = SensorKind::Stereo;
            c
        } else {
            Camera::tum_fr3()
        };
        camera.fps = 30.0;
        let input = frame(camera.width as usize, camera.height as usize, stereo);
        let chain = Chain::parse(&format!("{}:{}", f.name(), level(f))).expect("valid");
        let p = Perturber::new(&chain, &camera, 5000.0, 0, 10, "bench").expect("applies");
        let read = |_: usize| -> Result<FrameInput, datasets::DatasetError> { Ok(input.clone()) };
        group.bench_function(format!("{}:{}", f.name(), level(f)), |b| {
            b.iter(|| p.frame(1, &read).expect("perturbs"))
        });
    }
    group.finish();
}

criterion_group!(perturbations, benches);
criterion_main!(perturbations);
