//! `noisefree features`: detects ORB features on one image (optionally with its depth image or
//! the right image of a rectified pair), builds a slam-core `Frame` from them and draws the
//! keypoints into a PNG: circle radius by octave, a tick along the orientation, colour by depth
//! (RGB-D / stereo) or yellow when no depth source is given; keypoints without depth are red.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context};
use slam_core::feature::{OrbConfig, OrbExtractor};
use slam_core::frame::Frame;
use slam_core::{Camera, DepthImage, FrameInput, GrayImage, SensorKind};

/// Arguments of `noisefree features`.
#[derive(clap::Args, Debug)]
pub struct FeaturesArgs {
    /// Grey or colour PNG to extract features from (the left image of a stereo pair).
    pub image: PathBuf,
    /// Registered 16-bit depth PNG (TUM layout); keypoints get their depth from it.
    #[arg(long, conflicts_with = "right")]
    pub depth: Option<PathBuf>,
    /// Right image of a rectified stereo pair; keypoints get their depth by stereo matching.
    #[arg(long)]
    pub right: Option<PathBuf>,
    /// Output PNG with the keypoints drawn.
    #[arg(long)]
    pub out: PathBuf,
    /// Depth PNG units per metre (TUM: 5000).
    #[arg(long, default_value_t = 5000.0)]
    pub depth_factor: f64,
    /// Focal length in pixels (default: TUM fr3 535.4 for RGB-D, EuRoC 435.2 for stereo).
    #[arg(long)]
    pub fx: Option<f64>,
    /// Baseline times fx, metres * pixels (default: 40 for RGB-D, EuRoC 47.9 for stereo).
    #[arg(long)]
    pub bf: Option<f64>,
    /// Number of features (default 1000; 1200 with --right).
    #[arg(long)]
    pub n_features: Option<usize>,
}

/// Runs `noisefree features`.
pub fn run(args: FeaturesArgs) -> anyhow::Result<()> {
    let image = read_gray(&args.image)?;
    let stereo = args.right.is_some();
    let mut camera = Camera::tum_fr3();
    camera.width = image.width as u32;
    camera.height = image.height as u32;
    camera.cx = image.width as f64 / 2.0;
    camera.cy = image.height as f64 / 2.0;
    if stereo {
        camera.sensor = SensorKind::Stereo;
        camera.fx = 435.2046959714599;
        camera.fy = camera.fx;
        camera.bf = 47.90639384423901;
    }
    if let Some(fx) = args.fx {
        camera.fx = fx;
        camera.fy = fx;
    }
    if let Some(bf) = args.bf {
        camera.bf = bf;
    }
    let depth = match &args.depth {
        Some(p) => Some(Arc::new(read_depth(p, args.depth_factor, &image)?)),
        None => None,
    };
    let right = match &args.right {
        Some(p) => {
            let r = read_gray(p)?;
            if (r.width, r.height) != (image.width, image.height) {
                bail!(
                    "{}: right image is {}x{}, left is {}x{}",
                    p.display(),
                    r.width,
                    r.height,
                    image.width,
                    image.height
                );
            }
            Some(Arc::new(r))
        }
        None => None,
    };
    let mut cfg = if stereo {
        OrbConfig::stereo()
    } else {
        OrbConfig::default()
    };
    if let Some(n) = args.n_features {
        cfg.n_features = n;
    }
    let input = FrameInput {
        timestamp: 0.0,
        image: Arc::new(image),
        depth,
        right,
        colour: None,
    };
    let mut extractor = OrbExtractor::new(cfg);
    let start = std::time::Instant::now();
    let frame = Frame::new(0, &input, &camera, &mut extractor);
    let elapsed = start.elapsed();
    let has_depth_source = input.depth.is_some() || input.right.is_some();
    let picture = draw(&input.image, &frame, has_depth_source);
    write_png(&args.out, &picture)?;
    let mut per_octave = vec![0usize; frame.scale.n_levels];
    for kp in &frame.keypoints {
        per_octave[kp.octave] += 1;
    }
    println!(
        "{}: {} keypoints (per octave {:?}), {} with depth, frame built in {:.1} ms -> {}",
        args.image.display(),
        frame.len(),
        per_octave,
        frame.n_with_depth(),
        elapsed.as_secs_f64() * 1e3,
        args.out.display()
    );
    Ok(())
}

/// Reads a PNG as 8-bit grey.
fn read_gray(path: &Path) -> anyhow::Result<GrayImage> {
    // The header is checked before the pixels are allocated (datasets::decode).
    let img = datasets::decode::read_image(path)?.to_luma8();
    Ok(GrayImage {
        width: img.width() as usize,
        height: img.height() as usize,
        data: img.into_raw(),
    })
}

/// Reads a 16-bit depth PNG into metres (`value / factor`, 0 = no depth).
fn read_depth(path: &Path, factor: f64, image: &GrayImage) -> anyhow::Result<DepthImage> {
    if factor.is_nan() || factor <= 0.0 {
        bail!("--depth-factor must be positive, got {factor}");
    }
    let img = datasets::decode::read_image(path)?.to_luma16();
    let (w, h) = (img.width() as usize, img.height() as usize);
    if (w, h) != (image.width, image.height) {
        bail!(
            "{}: depth image is {w}x{h}, grey image is {}x{}",
            path.display(),
            image.width,
            image.height
        );
    }
    Ok(DepthImage {
        width: w,
        height: h,
        data: img
            .into_raw()
            .into_iter()
            .map(|v| (v as f64 / factor) as f32)
            .collect(),
    })
}

/// Colour of a depth in metres: near (0.5 m) blue through green to far (5 m) orange.
fn depth_colour(d: f32) -> [u8; 3] {
    let t = ((d - 0.5) / 4.5).clamp(0.0, 1.0);
    let lerp = |a: f32, b: f32, s: f32| (a + (b - a) * s).round() as u8;
    if t < 0.5 {
        let s = t * 2.0;
        [
            lerp(40.0, 40.0, s),
            lerp(110.0, 220.0, s),
            lerp(255.0, 60.0, s),
        ]
    } else {
        let s = (t - 0.5) * 2.0;
        [
            lerp(40.0, 255.0, s),
            lerp(220.0, 150.0, s),
            lerp(60.0, 0.0, s),
        ]
    }
}

/// The grey image in colour with every raw keypoint drawn on it.
fn draw(img: &GrayImage, frame: &Frame, has_depth_source: bool) -> image::RgbImage {
    let mut out = image::RgbImage::from_fn(img.width as u32, img.height as u32, |x, y| {
        let v = img.get(x as usize, y as usize) / 2 + 40;
        image::Rgb([v, v, v])
    });
    let mut put = |x: f32, y: f32, c: [u8; 3]| {
        let (xi, yi) = (x.round() as i64, y.round() as i64);
        if xi >= 0 && yi >= 0 && (xi as u32) < out.width() && (yi as u32) < out.height() {
            out.put_pixel(xi as u32, yi as u32, image::Rgb(c));
        }
    };
    for (i, kp) in frame.keypoints_raw.iter().enumerate() {
        let colour = if !has_depth_source {
            [255, 230, 0]
        } else if frame.depth[i] > 0.0 {
            depth_colour(frame.depth[i])
        } else {
            [255, 40, 40]
        };
        let r = 3.0 * frame.scale.scale_factors[kp.octave] as f32;
        let n = (2.0 * std::f32::consts::PI * r).ceil() as usize * 2;
        for k in 0..n {
            let a = k as f32 / n as f32 * std::f32::consts::TAU;
            put(kp.x + r * a.cos(), kp.y + r * a.sin(), colour);
        }
        let (s, c) = kp.angle.to_radians().sin_cos();
        for k in 0..=(r.ceil() as usize * 2) {
            let t = k as f32 / 2.0;
            put(kp.x + t * c, kp.y + t * s, colour);
        }
    }
    out
}

/// Writes the PNG through a temporary file in the same directory, then renames it.
fn write_png(path: &Path, img: &image::RgbImage) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create directory", dir.display()))?;
    }
    let tmp = path.with_extension("png.tmp");
    img.save_with_format(&tmp, image::ImageFormat::Png)
        .with_context(|| format!("{}: cannot write PNG", tmp.display()))?;
    std::fs::rename(&tmp, path)
        .with_context(|| format!("{}: cannot rename into place", path.display()))?;
    Ok(())
}
