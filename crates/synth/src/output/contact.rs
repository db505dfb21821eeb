//! A contact sheet: a few frames of a sequence side by side at half resolution, one row per
//! frame. RGB-D: colour | measured depth (jet, 0.4-5 m, holes black) | depth error (measured
//! minus true, blue-white-red over +-5 cm, holes black). Stereo: left | right | true depth.

use std::path::Path;

use image::{Rgb, RgbImage};

use crate::error::SynthError;
use crate::generator::{Generator, SynthFrame};

const GAP: u32 = 4;

/// Wraps an I/O error with its path.
fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> SynthError + '_ {
    move |source| SynthError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn jet(x: f64) -> [u8; 3] {
    let c = |o: f64| ((1.5 - (4.0 * x - o).abs()).clamp(0.0, 1.0) * 255.0) as u8;
    [c(3.0), c(2.0), c(1.0)]
}

fn diverging(e: f64) -> [u8; 3] {
    let x = (e / 0.05).clamp(-1.0, 1.0);
    let f = |v: f64| (v * 255.0) as u8;
    if x >= 0.0 {
        [255, f(1.0 - x), f(1.0 - x)]
    } else {
        [f(1.0 + x), f(1.0 + x), 255]
    }
}

/// The three tiles of one frame, full resolution, as RGB per pixel.
fn tiles(f: &SynthFrame) -> [Vec<[u8; 3]>; 3] {
    let n = f.gray.width * f.gray.height;
    let grey = |d: &[u8]| d.iter().map(|&g| [g, g, g]).collect::<Vec<_>>();
    let first = match &f.rgb {
        Some(rgb) => rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        None => grey(&f.gray.data),
    };
    let depth_map = |d: &[f32]| {
        d.iter()
            .map(|&z| {
                if z > 0.0 {
                    jet(((z as f64 - 0.4) / 4.6).clamp(0.0, 1.0))
                } else {
                    [0, 0, 0]
                }
            })
            .collect::<Vec<_>>()
    };
    let truth = f
        .depth_true
        .as_ref()
        .map(|d| d.data.clone())
        .unwrap_or_else(|| vec![0.0; n]);
    match (&f.depth, &f.right) {
        (Some(d), _) => {
            let err = d
                .data
                .iter()
                .zip(&truth)
                .map(|(&m, &t)| {
                    if m > 0.0 {
                        diverging(m as f64 - t as f64)
                    } else {
                        [0, 0, 0]
                    }
                })
                .collect();
            [first, depth_map(&d.data), err]
        }
        (None, Some(r)) => [first, grey(&r.data), depth_map(&truth)],
        (None, None) => [first, depth_map(&truth), vec![[0, 0, 0]; n]],
    }
}

/// Renders a contact sheet of the given frame indices.
pub fn contact_sheet(gen: &Generator, frames: &[usize]) -> RgbImage {
    let cam = gen.camera();
    let (w, h) = (cam.width / 2, cam.height / 2);
    let sheet_w = 3 * w + 4 * GAP;
    let sheet_h = frames.len() as u32 * (h + GAP) + GAP;
    let mut img = RgbImage::from_pixel(sheet_w, sheet_h, Rgb([255, 255, 255]));
    for (row, &i) in frames.iter().enumerate() {
        let f = gen.frame(i);
        let fw = f.gray.width;
        for (col, tile) in tiles(&f).iter().enumerate() {
            let x0 = GAP + col as u32 * (w + GAP);
            let y0 = GAP + row as u32 * (h + GAP);
            for y in 0..h {
                for x in 0..w {
                    // 2x2 box filter.
                    let mut acc = [0u32; 3];
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let p = tile[(2 * y + dy) as usize * fw + (2 * x + dx) as usize];
                        for k in 0..3 {
                            acc[k] += p[k] as u32;
                        }
                    }
                    img.put_pixel(x0 + x, y0 + y, Rgb(acc.map(|a| ((a + 2) / 4) as u8)));
                }
            }
        }
    }
    img
}

/// Writes a contact sheet of `rows` frames spread evenly over the first `n` frames to `path`
/// (PNG, via a temporary file renamed into place).
pub fn write_contact_sheet(
    gen: &Generator,
    n: usize,
    rows: usize,
    path: &Path,
) -> Result<(), SynthError> {
    gen.check_frames(n)?;
    let rows = rows.clamp(1, n.max(1));
    let frames: Vec<usize> = (0..rows)
        .map(|r| (r * n.max(1)) / rows + n.max(1) / (2 * rows))
        .map(|i| i.min(n.max(1) - 1))
        .collect();
    let img = contact_sheet(gen, &frames);
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(io_err(parent))?;
    }
    // `.jpg` / `.jpeg`: JPEG at quality 90 (a sixth of the PNG's size on noisy frames, for
    // sheets kept in the repository); anything else: PNG.
    let jpeg = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("jpg") || e.eq_ignore_ascii_case("jpeg"));
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let written = if jpeg {
        std::fs::File::create(&tmp)
            .map_err(io_err(&tmp))
            .and_then(|f| {
                let mut w = std::io::BufWriter::new(f);
                image::codecs::jpeg::JpegEncoder::new_with_quality(&mut w, 90)
                    .encode_image(&img)
                    .map_err(|source| SynthError::Image {
                        path: tmp.clone(),
                        source,
                    })
            })
    } else {
        img.save_with_format(&tmp, image::ImageFormat::Png)
            .map_err(|source| SynthError::Image {
                path: tmp.clone(),
                source,
            })
    };
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(io_err(path))
}
