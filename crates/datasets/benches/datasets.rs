//! Benchmarks of the per-frame costs of the readers: rectifying a 752x480 EuRoC image with
//! precomputed maps, building the maps, and decoding a 640x480 TUM colour + depth PNG pair.

use criterion::{criterion_group, criterion_main, Criterion};
use datasets::decode::{read_depth, read_gray};
use datasets::rectify::{RawCamera, StereoRectification};
use nalgebra::{Isometry3, Vector3};
use slam_core::{Distortion, GrayImage};

fn euroc_like() -> (RawCamera, RawCamera) {
    let left = RawCamera {
        width: 752,
        height: 480,
        fx: 458.654,
        fy: 457.296,
        cx: 367.215,
        cy: 248.375,
        distortion: Distortion {
            k1: -0.28340811,
            k2: 0.07395907,
            p1: 0.00019359,
            p2: 1.76187114e-05,
            k3: 0.0,
        },
        t_bs: Isometry3::identity(),
        rate_hz: 20.0,
    };
    let right = RawCamera {
        t_bs: Isometry3::new(
            Vector3::new(0.11, 0.0, 0.0),
            Vector3::new(0.003, -0.002, 0.001),
        ),
        ..left.clone()
    };
    (left, right)
}

fn benches(c: &mut Criterion) {
    let (l, r) = euroc_like();
    c.bench_function("rectification maps 752x480 (both cameras)", |b| {
        b.iter(|| StereoRectification::new(&l, &r).unwrap())
    });
    let rect = StereoRectification::new(&l, &r).unwrap();
    let img = GrayImage {
        width: 752,
        height: 480,
        data: (0..752 * 480).map(|i| (i * 31 % 251) as u8).collect(),
    };
    c.bench_function("rectify one 752x480 image", |b| {
        b.iter(|| rect.rectify_left(&img))
    });

    let dir = tempfile::tempdir().unwrap();
    let rgb_path = dir.path().join("rgb.png");
    let depth_path = dir.path().join("depth.png");
    image::RgbImage::from_fn(640, 480, |x, y| {
        image::Rgb([(x * 3 + y) as u8, (x ^ y) as u8, (x * y % 256) as u8])
    })
    .save(&rgb_path)
    .unwrap();
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(640, 480, |x, y| {
        image::Luma([(5000 + x * 10 + y * 7) as u16])
    })
    .save(&depth_path)
    .unwrap();
    c.bench_function("decode TUM 640x480 rgb + depth PNG", |b| {
        b.iter(|| {
            (
                read_gray(&rgb_path).unwrap(),
                read_depth(&depth_path, 5000.0).unwrap(),
            )
        })
    });
}

criterion_group!(name = group; config = Criterion::default().sample_size(20); targets = benches);
criterion_main!(group);
