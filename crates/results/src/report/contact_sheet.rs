//! The contact sheet of a perturbed copy (`noisefree perturb --contact-sheet`): four frames,
//! each row the input and the perturbed images side by side (RGB-D: grey and depth of both;
//! stereo: the input left image and the perturbed pair), with the columns titled, each row's
//! frame number, the chain as a caption and the depth colour scale, so the sheet reads on its
//! own in a paper or an issue.

use crate::report::figures::{err, register_font};
use anyhow::{Context, Result};
use datasets::FrameReader;
use plotters::prelude::*;
use slam_core::{DepthImage, GrayImage};
use std::path::Path;

/// Depth range of the colour scale, metres (Kinect's working range).
const DEPTH_RANGE: (f32, f32) = (0.4, 5.0);

/// The colour of depth `z` (metres): black without a reading, red near to blue far.
fn depth_colour(z: f32) -> [u8; 3] {
    if z <= 0.0 || !z.is_finite() {
        return [0, 0, 0];
    }
    let t = ((z - DEPTH_RANGE.0) / (DEPTH_RANGE.1 - DEPTH_RANGE.0)).clamp(0.0, 1.0);
    [
        (255.0 * (1.0 - t)) as u8,
        (255.0 * (1.0 - (2.0 * t - 1.0).abs())) as u8,
        (255.0 * t) as u8,
    ]
}

/// One tile: an image at half resolution as RGB pixels.
enum Tile<'a> {
    Grey(&'a GrayImage),
    Depth(&'a DepthImage),
}

impl Tile<'_> {
    /// The pixel at half-resolution (x, y).
    fn at(&self, x: usize, y: usize) -> [u8; 3] {
        match self {
            Tile::Grey(g) => {
                let v = g.data[(2 * y) * g.width + 2 * x];
                [v, v, v]
            }
            Tile::Depth(d) => depth_colour(d.data[(2 * y) * d.width + 2 * x]),
        }
    }
}

/// Writes the sheet of `out` (the perturbed frames; `sources[i]`: the input frame output frame
/// i shows) against `input` to `path` (PNG), captioned `caption`.
pub fn write(
    input: &FrameReader,
    out: &FrameReader,
    sources: &[usize],
    caption: &str,
    path: &Path,
) -> Result<()> {
    let n = out.len();
    let rows: Vec<usize> = (0..4.min(n)).map(|r| (r * n + n / 8) / 4.min(n)).collect();
    let first = out.read(0)?;
    let rgbd = first.depth.is_some();
    let titles: &[&str] = match (rgbd, first.right.is_some()) {
        (true, _) => &["input", "perturbed", "input depth", "perturbed depth"],
        (false, true) => &["input left", "perturbed left", "perturbed right"],
        (false, false) => &["input", "perturbed"],
    };
    let (w, h) = (first.image.width / 2, first.image.height / 2);
    let (gap, left, top) = (6, 90, 78);
    let bottom = if rgbd { 70 } else { 10 };
    let width = left + titles.len() * (w + gap);
    let height = top + rows.len() * (h + gap) + bottom;
    let mut pixels = vec![255u8; width * height * 3];
    for (r, &i) in rows.iter().enumerate() {
        let (a, b) = (input.read(sources[i])?, out.read(i)?);
        let mut tiles = vec![Tile::Grey(&a.image), Tile::Grey(&b.image)];
        match (&a.depth, &b.depth, &b.right) {
            (Some(da), Some(db), _) => tiles.extend([Tile::Depth(da), Tile::Depth(db)]),
            (_, _, Some(right)) => tiles.push(Tile::Grey(right)),
            _ => {}
        }
        for (c, tile) in tiles.iter().take(titles.len()).enumerate() {
            let (x0, y0) = (left + c * (w + gap), top + r * (h + gap));
            for y in 0..h {
                for x in 0..w {
                    let k = 3 * ((y0 + y) * width + x0 + x);
                    pixels[k..k + 3].copy_from_slice(&tile.at(x, y));
                }
            }
        }
    }
    register_font();
    {
        let area = BitMapBackend::with_buffer(&mut pixels, (width as u32, height as u32))
            .into_drawing_area();
        let text = |s: &str, x: usize, y: usize, px: u32| {
            area.draw(&Text::new(
                s.to_string(),
                (x as i32, y as i32),
                ("sans-serif", px).into_font().color(&BLACK),
            ))
            .map_err(err)
        };
        text(caption, left, 10, 22)?;
        for (c, t) in titles.iter().enumerate() {
            text(t, left + c * (w + gap), top - 28, 18)?;
        }
        for (r, &i) in rows.iter().enumerate() {
            text(
                &format!("frame {i}"),
                8,
                top + r * (h + gap) + h / 2 - 9,
                16,
            )?;
        }
        if rgbd {
            // The depth scale under the depth columns: the colours from near to far.
            let x0 = left + 2 * (w + gap);
            let y0 = top + rows.len() * (h + gap) + 12;
            let bar = 2 * w + gap;
            for x in 0..bar {
                let z = DEPTH_RANGE.0 + (DEPTH_RANGE.1 - DEPTH_RANGE.0) * x as f32 / bar as f32;
                let [r, g, b] = depth_colour(z);
                area.draw(&Rectangle::new(
                    [
                        ((x0 + x) as i32, y0 as i32),
                        ((x0 + x + 1) as i32, (y0 + 16) as i32),
                    ],
                    RGBColor(r, g, b).filled(),
                ))
                .map_err(err)?;
            }
            text(&format!("{} m", DEPTH_RANGE.0), x0, y0 + 22, 16)?;
            text(&format!("{} m", DEPTH_RANGE.1), x0 + bar - 40, y0 + 22, 16)?;
            text("depth (black: no reading)", x0 + bar / 2 - 100, y0 + 22, 16)?;
        }
        area.present().map_err(err)?;
    }
    let img = image::RgbImage::from_raw(width as u32, height as u32, pixels)
        .context("the contact sheet's buffer")?;
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .context("encoding the contact sheet")?;
    atomic_file::write(path, &bytes)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use slam_core::FrameInput;
    use std::sync::Arc;

    /// A reader of `n` 64x48 RGB-D frames of grey `v` and depth `z` metres.
    fn frames(n: usize, v: u8, z: f32) -> FrameReader {
        FrameReader::new(n, move |i| {
            Ok(FrameInput {
                timestamp: i as f64,
                image: Arc::new(GrayImage {
                    width: 64,
                    height: 48,
                    data: vec![v; 64 * 48],
                }),
                depth: Some(Arc::new(DepthImage {
                    width: 64,
                    height: 48,
                    data: vec![z; 64 * 48],
                })),
                right: None,
                colour: None,
            })
        })
    }

    /// An RGB-D sheet shows the input's depth beside the perturbed depth (the old sheet showed
    /// only the perturbed one), and carries its titles and scale.
    #[test]
    fn an_rgbd_sheet_shows_both_depths_titled() {
        let dir = std::env::temp_dir().join(format!("nf-sheet-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("sheet.png");
        let sources: Vec<usize> = (0..8).collect();
        write(
            &frames(8, 100, 1.0),
            &frames(8, 200, 4.0),
            &sources,
            "test: depth-axial:8",
            &path,
        )
        .unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        let (w, h, gap, left, top) = (32u32, 24u32, 6u32, 90u32, 78u32);
        assert_eq!(img.width(), left + 4 * (w + gap));
        assert_eq!(img.height(), top + 4 * (h + gap) + 70);
        let at = |c: u32, r: u32| {
            img.get_pixel(left + c * (w + gap) + w / 2, top + r * (h + gap) + h / 2)
                .0
        };
        assert_eq!(at(0, 0), [100, 100, 100], "input grey");
        assert_eq!(at(1, 0), [200, 200, 200], "perturbed grey");
        assert_eq!(at(2, 0), depth_colour(1.0), "input depth");
        assert_eq!(at(3, 3), depth_colour(4.0), "perturbed depth");
        let inked = (0..img.width())
            .flat_map(|x| (0..top - 5).map(move |y| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0 != [255, 255, 255])
            .count();
        assert!(inked > 100, "caption and titles drawn: {inked} pixels");
        let _ = std::fs::remove_dir_all(dir);
    }
}
