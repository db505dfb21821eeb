//! Helpers shared by the integration tests: tiny TUM RGB-D folders written with `image`.

#![allow(dead_code)]

use slam_core::Camera;
use std::path::Path;

/// A small fr3-like camera for W x H test images.
pub fn small_camera(w: u32, h: u32) -> Camera {
    Camera {
        width: w,
        height: h,
        cx: w as f64 / 2.0,
        cy: h as f64 / 2.0,
        ..Camera::tum_fr3()
    }
}

/// Writes a TUM folder with `n` frames of W x H: rgb i has value 10 + i everywhere (grey
/// RGB), depth i is 5000 + i (1 m + i/5000 m). Returns nothing; the folder is `dir`.
pub fn write_tum(dir: &Path, n: usize, w: u32, h: u32) {
    std::fs::create_dir_all(dir.join("rgb")).unwrap();
    std::fs::create_dir_all(dir.join("depth")).unwrap();
    let mut rgb_txt = String::from("# color images\n# file: 'test'\n# timestamp filename\n");
    let mut depth_txt = String::from("# depth maps\n# file: 'test'\n# timestamp filename\n");
    let mut gt = String::from("# timestamp tx ty tz qx qy qz qw\n");
    for i in 0..n {
        let t = 1000.0 + i as f64 / 30.0;
        let v = 10 + i as u8;
        let rgb = image::RgbImage::from_pixel(w, h, image::Rgb([v, v, v]));
        rgb.save(dir.join(format!("rgb/{t:.6}.png"))).unwrap();
        let d = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(
            w,
            h,
            image::Luma([5000 + i as u16]),
        );
        // depth stamps are 5 ms later, as the Kinect's are.
        d.save(dir.join(format!("depth/{:.6}.png", t + 0.005)))
            .unwrap();
        rgb_txt += &format!("{t:.6} rgb/{t:.6}.png\n");
        depth_txt += &format!("{:.6} depth/{:.6}.png\n", t + 0.005, t + 0.005);
        gt += &format!("{t:.4} {} 0 0 0 0 0 1\n", i as f64 * 0.01);
    }
    std::fs::write(dir.join("rgb.txt"), rgb_txt).unwrap();
    std::fs::write(dir.join("depth.txt"), depth_txt).unwrap();
    std::fs::write(dir.join("groundtruth.txt"), gt).unwrap();
}
