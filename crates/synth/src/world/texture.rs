//! Procedural textures rich in corners at several scales: collages of random rectangles,
//! triangles, discs and text-like glyph blocks over a patchwork background, rasterised once per
//! surface (metric texel size) and sampled bilinearly at render time.
//!
//! Nothing is periodic: every shape's position, size, angle and colour is drawn from the scene
//! RNG, so ORB descriptors stay distinctive. Shapes are drawn from large to small, so small
//! high-contrast corners sit on top of large ones and every pyramid level finds structure.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Look of a surface's collage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    /// Posters, shapes and text on a patchwork: walls, boxes, clothes.
    Poster,
    /// Carpet-like patchwork of random tiles with scattered shapes: floors.
    Carpet,
    /// Wood-like streaks with papers and text on top: the table.
    Desk,
    /// An office wall or cabinet: a plain painted surface with faint shading and a few posters,
    /// pictures and notes, as real offices have (most of a real wall gives ORB nothing).
    OfficeWall,
    /// Office carpet tiles: large, low-contrast.
    OfficeFloor,
    /// Clothing: a dyed cloth with shading folds, stripes on some, a print on some.
    Cloth,
    /// A head wrapped on a cylinder (u round it from behind, v up): skin, hair on top and at
    /// the back, eyes and mouth at the front.
    Head,
    /// A padded gym mat as EuRoC's Vicon rooms line their walls with: grey fabric with faint
    /// shading and darker quilting seams every 25-50 cm (seen on the real V1_01 frames: big,
    /// nearly textureless surfaces).
    Mat,
    /// Curtain or plain panel: a light surface with soft vertical folds (the Vicon room's
    /// walls above the mats).
    Curtain,
    /// A black tape strip with white chips, as the markers laid on the Vicon room's floor.
    MarkerStrip,
    /// A black-and-white calibration checkerboard of 5 cm squares.
    Checker,
    /// Concrete or painted industrial surface: large grey slabs with stains, a few painted
    /// lines and signs (the machine hall's floor and walls).
    Concrete,
    /// Machinery: a painted body in panels with labels, vents and bolts.
    Machine,
    /// Leaves and stems of a house plant: patches of dark and light green with paler veins
    /// and a few brown or yellow spots.
    Foliage,
    /// The plush of a teddy bear: a brown or golden pile of small shaded tufts with darker
    /// flecks and a few stitched patches.
    Fur,
}

/// An RGB texture covering `width_m` x `height_m` metres of a surface.
#[derive(Clone, Debug)]
pub struct Texture {
    w: usize,
    h: usize,
    /// Texels per metre.
    scale: f64,
    data: Vec<[u8; 3]>,
}

/// A random colour whose luminance lies in one of three well-separated bands, so that two
/// neighbouring shapes usually differ by 60+ grey levels.
fn random_colour(rng: &mut ChaCha8Rng) -> [u8; 3] {
    let band = rng.random_range(0..3);
    let lum: f64 = match band {
        0 => rng.random_range(15.0..70.0),
        1 => rng.random_range(105.0..155.0),
        _ => rng.random_range(190.0..250.0),
    };
    let sat: f64 = rng.random_range(0.0..0.6);
    let hue: [f64; 3] = [
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    ];
    // Remove the hue's luminance so the colour keeps its band.
    let hl = 0.299 * hue[0] + 0.587 * hue[1] + 0.114 * hue[2];
    let amp = sat * lum.min(255.0 - lum).max(20.0);
    let c = |i: usize| (lum + amp * (hue[i] - hl)).clamp(0.0, 255.0) as u8;
    [c(0), c(1), c(2)]
}

/// Recursive random split of a rectangle into tiles between `min` and `max` metres wide;
/// `leaf(rng, x, y, w, h)` runs on each tile as the recursion reaches it (so a leaf that draws
/// from `rng` interleaves its draws with the splits).
#[allow(clippy::too_many_arguments)]
fn split_tiles(
    rng: &mut ChaCha8Rng,
    x: f64,
    y: f64,
    w: f64,
    h: f64,
    min: f64,
    max: f64,
    leaf: &mut impl FnMut(&mut ChaCha8Rng, f64, f64, f64, f64),
) {
    let split_x = w > max || (w > 2.0 * min && rng.random_bool(0.5) && w >= h);
    let split_y = h > max || (h > 2.0 * min && rng.random_bool(0.5));
    if split_x && w > 2.0 * min {
        let f = rng.random_range(0.3..0.7);
        split_tiles(rng, x, y, w * f, h, min, max, leaf);
        split_tiles(rng, x + w * f, y, w * (1.0 - f), h, min, max, leaf);
    } else if split_y && h > 2.0 * min {
        let f = rng.random_range(0.3..0.7);
        split_tiles(rng, x, y, w, h * f, min, max, leaf);
        split_tiles(rng, x, y + h * f, w, h * (1.0 - f), min, max, leaf);
    } else {
        leaf(rng, x, y, w, h);
    }
}

impl Texture {
    /// Rasterises a new collage texture of the given metric size and texel size (metres).
    pub fn collage(
        rng: &mut ChaCha8Rng,
        width_m: f64,
        height_m: f64,
        texel_m: f64,
        style: Style,
    ) -> Texture {
        let scale = 1.0 / texel_m;
        let w = ((width_m * scale).ceil() as usize).max(4);
        let h = ((height_m * scale).ceil() as usize).max(4);
        let mut t = Texture {
            w,
            h,
            scale,
            data: vec![random_colour(rng); w * h],
        };
        let (wm, hm) = (w as f64 / scale, h as f64 / scale);
        match style {
            Style::Carpet => t.paint_carpet(rng, wm, hm, texel_m),
            Style::Poster => t.paint_poster(rng, wm, hm, texel_m),
            Style::Desk => t.paint_desk(rng, wm, hm, texel_m),
            Style::OfficeWall => t.paint_office_wall(rng, wm, hm, texel_m),
            Style::OfficeFloor => t.paint_office_floor(rng, wm, hm),
            Style::Cloth => t.paint_cloth(rng, wm, hm, texel_m),
            Style::Head => t.paint_head(rng, wm, hm),
            Style::Mat => t.paint_mat(rng, wm, hm, texel_m),
            Style::Curtain => t.paint_curtain(rng, wm, hm),
            Style::MarkerStrip => t.paint_marker_strip(rng, wm, hm),
            Style::Checker => t.paint_checker(rng, wm, hm),
            Style::Concrete => t.paint_concrete(rng, wm, hm, texel_m),
            Style::Machine => t.paint_machine(rng, wm, hm, texel_m),
            Style::Foliage => t.paint_foliage(rng, wm, hm),
            Style::Fur => t.paint_fur(rng, wm, hm, texel_m),
        }
        t
    }

    /// Paints [`Style::Carpet`]: a patchwork of tiles, shapes scattered at three scales.
    fn paint_carpet(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        self.patchwork(rng, 0.0, 0.0, wm, hm, 0.08, 0.6);
        self.scatter(
            rng,
            wm,
            hm,
            &[(0.2, 0.3), (0.1, 0.25), (0.05, 0.15)],
            0.0,
            texel_m,
        );
    }

    /// Paints [`Style::Poster`]: a coarse patchwork, shapes and text scattered at five scales.
    fn paint_poster(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        self.patchwork(rng, 0.0, 0.0, wm, hm, 0.3, 1.2);
        let scales = [
            (0.45, 0.4),
            (0.22, 0.35),
            (0.11, 0.3),
            (0.055, 0.2),
            (0.028, 0.1),
        ];
        self.scatter(rng, wm, hm, &scales, 0.15, texel_m);
    }

    /// Paints [`Style::Desk`]: wood-like streaks, papers and text on top.
    fn paint_desk(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        self.streaks(rng, wm, hm);
        let scales = [(0.2, 0.3), (0.1, 0.25), (0.05, 0.2), (0.025, 0.1)];
        self.scatter(rng, wm, hm, &scales, 0.25, texel_m);
    }

    /// Paints [`Style::OfficeWall`]: shaded paint, framed posters over about 12 % of it, notes.
    fn paint_office_wall(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        let paint = [rng.random_range(150.0..215.0), rng.random_range(0.0..0.25)];
        self.shaded_patchwork(rng, wm, hm, (0.6, 2.0), paint, 6.0);
        // Posters and pictures covering ~12 % of the surface, each framed.
        let n = (0.12 * wm * hm / 0.3).ceil() as usize;
        for _ in 0..n {
            let pw = rng.random_range(0.25..0.8f64).min(0.9 * wm);
            let ph = rng.random_range(0.25..0.8f64).min(0.9 * hm);
            let x0 = rng.random_range(0.0..(wm - pw).max(1e-3));
            let y0 = rng.random_range(0.0..(hm - ph).max(1e-3));
            let frame = random_colour(rng);
            self.fill_rect(x0 - 0.01, y0 - 0.01, x0 + pw + 0.01, y0 + ph + 0.01, frame);
            let poster = Texture::collage(rng, pw, ph, texel_m, Style::Poster);
            self.blit(&poster, x0, y0);
        }
        // A few notes.
        self.scatter(rng, wm, hm, &[(0.2, 0.01)], 1.0, texel_m);
    }

    /// Paints [`Style::OfficeFloor`]: large low-contrast tiles.
    fn paint_office_floor(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let grey = [rng.random_range(70.0..130.0), rng.random_range(0.0..0.2)];
        self.shaded_patchwork(rng, wm, hm, (0.5, 0.5), grey, 7.0);
    }

    /// Paints [`Style::Cloth`]: dyed shaded folds, stripes on some, a print.
    fn paint_cloth(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        let dye = [rng.random_range(40.0..200.0), rng.random_range(0.1..0.6)];
        self.shaded_patchwork(rng, wm, hm, (0.04, 0.15), dye, 22.0);
        if rng.random_bool(0.4) {
            // Stripes of a second colour.
            let c = random_colour(rng);
            let (w, gap) = (rng.random_range(0.01..0.03), rng.random_range(0.02..0.06));
            let mut y = 0.0;
            while y < hm {
                self.fill_rect(0.0, y, wm, y + w, c);
                y += w + gap;
            }
        }
        self.scatter(rng, wm, hm, &[(0.06, 0.04), (0.03, 0.03)], 0.0, texel_m);
    }

    /// Paints [`Style::Head`]: skin, hair on top and at the back, eyes and mouth at the front.
    fn paint_head(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let skin = [rng.random_range(120.0..200.0), rng.random_range(0.2..0.4)];
        self.shaded_patchwork(rng, wm, hm, (0.03, 0.08), skin, 8.0);
        let l = rng.random_range(20.0..90.0);
        let hair = [l as u8, (l * 0.85) as u8, (l * 0.7) as u8];
        let front = 0.5 * wm;
        // Hair: the top third all round, down to the neck at the back.
        self.fill_rect(0.0, 0.62 * hm, wm, hm, hair);
        self.fill_rect(0.0, 0.0, 0.22 * wm, hm, hair);
        self.fill_rect(0.78 * wm, 0.0, wm, hm, hair);
        let dark = [40, 30, 30];
        self.fill_disc(front - 0.03, 0.5 * hm, 0.008, dark);
        self.fill_disc(front + 0.03, 0.5 * hm, 0.008, dark);
        self.fill_rect(
            front - 0.025,
            0.22 * hm,
            front + 0.025,
            0.25 * hm,
            [120, 50, 50],
        );
    }

    /// Paints [`Style::Mat`]: grey shaded fabric, darker seams at a regular spacing, scuffs.
    fn paint_mat(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        let grey = [rng.random_range(110.0..170.0), rng.random_range(0.0..0.15)];
        self.shaded_patchwork(rng, wm, hm, (0.3, 1.0), grey, 4.0);
        let seam = rng.random_range(0.25..0.5);
        let dark = (grey[0] - rng.random_range(18.0..30.0)) as u8;
        let mut y = seam;
        while y < hm {
            self.fill_rect(0.0, y - 0.008, wm, y + 0.008, [dark; 3]);
            y += seam;
        }
        // Scuffs.
        self.scatter(rng, wm, hm, &[(0.04, 0.004)], 0.0, texel_m);
    }

    /// Paints [`Style::Curtain`]: light vertical folds.
    fn paint_curtain(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let base: f64 = rng.random_range(185.0..235.0);
        let mut x = 0.0;
        while x < wm {
            let w = rng.random_range(0.08..0.25);
            let l = (base + rng.random_range(-9.0..9.0)).clamp(0.0, 255.0) as u8;
            self.fill_rect(x, 0.0, x + w, hm, [l; 3]);
            x += w;
        }
    }

    /// Paints [`Style::MarkerStrip`]: black tape with rotated white chips.
    fn paint_marker_strip(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let black = rng.random_range(15..35);
        self.fill_rect(0.0, 0.0, wm, hm, [black; 3]);
        let n = (wm * hm / 0.0025).ceil() as usize;
        for _ in 0..n {
            let (cx, cy) = (rng.random_range(0.0..wm), rng.random_range(0.0..hm));
            let (hw, hh) = (rng.random_range(0.006..0.02), rng.random_range(0.003..0.01));
            let a = rng.random_range(0.0..std::f64::consts::PI);
            let (ca, sa) = (a.cos(), a.sin());
            let p = |x: f64, y: f64| (cx + ca * x - sa * y, cy + sa * x + ca * y);
            let white = rng.random_range(200..=250);
            self.fill_polygon(
                &[p(-hw, -hh), p(hw, -hh), p(hw, hh), p(-hw, hh)],
                [white; 3],
            );
        }
    }

    /// Paints [`Style::Checker`]: 5 cm squares inside a white margin.
    fn paint_checker(&mut self, _rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let sq = 0.05;
        self.fill_rect(0.0, 0.0, wm, hm, [235; 3]);
        let (nx, ny) = ((wm / sq) as usize, (hm / sq) as usize);
        for j in 1..ny.saturating_sub(1) {
            for i in 1..nx.saturating_sub(1) {
                if (i + j) % 2 == 0 {
                    let (x, y) = (i as f64 * sq, j as f64 * sq);
                    self.fill_rect(x, y, x + sq, y + sq, [20; 3]);
                }
            }
        }
    }

    /// Paints [`Style::Concrete`]: grey slabs, stains and cracks, painted lines and signs.
    fn paint_concrete(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        let grey = [rng.random_range(95.0..150.0), rng.random_range(0.0..0.12)];
        self.shaded_patchwork(rng, wm, hm, (0.8, 3.0), grey, 9.0);
        // Stains and cracks, then a few painted lines and signs.
        self.scatter(rng, wm, hm, &[(0.3, 0.02), (0.08, 0.01)], 0.0, texel_m);
        let lines = (wm * hm / 20.0).ceil() as usize;
        for _ in 0..lines {
            let paint = [230, rng.random_range(170..220), rng.random_range(0..60)];
            let y = rng.random_range(0.0..hm);
            self.fill_rect(0.0, y, wm, y + 0.08, paint);
        }
        let signs = (wm * hm / 15.0).ceil() as usize;
        for _ in 0..signs {
            let (pw, ph) = (rng.random_range(0.2..0.6), rng.random_range(0.2..0.6));
            let x0 = rng.random_range(0.0..(wm - pw).max(1e-3));
            let y0 = rng.random_range(0.0..(hm - ph).max(1e-3));
            let sign = Texture::collage(rng, pw, ph, texel_m, Style::Poster);
            self.blit(&sign, x0, y0);
        }
    }

    /// Paints [`Style::Machine`]: painted panels, labels, vents and bolts.
    fn paint_machine(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        let paint = [rng.random_range(60.0..190.0), rng.random_range(0.1..0.6)];
        self.shaded_patchwork(rng, wm, hm, (0.2, 0.8), paint, 25.0);
        // Labels, vents, bolts and cables.
        self.scatter(
            rng,
            wm,
            hm,
            &[(0.12, 0.06), (0.04, 0.05), (0.015, 0.03)],
            0.3,
            texel_m,
        );
    }

    /// Paints [`Style::Foliage`]: green patches, paler veins, brown or yellow spots.
    fn paint_foliage(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let mut tiles = Vec::new();
        split_tiles(rng, 0.0, 0.0, wm, hm, 0.02, 0.08, &mut |_, x, y, w, h| {
            tiles.push((x, y, w, h))
        });
        for (x, y, w, h) in tiles {
            let g: f64 = rng.random_range(50.0..190.0);
            let c = [(g * 0.45) as u8, g as u8, (g * 0.3) as u8];
            self.fill_rect(x, y, x + w, y + h, c);
        }
        // Veins: pale lines across, then spots.
        let mut y = rng.random_range(0.0..0.03);
        while y < hm {
            let l: f64 = rng.random_range(170.0..230.0);
            let c = [(l * 0.75) as u8, l as u8, (l * 0.5) as u8];
            self.fill_rect(0.0, y, wm, y + 0.003, c);
            y += rng.random_range(0.015..0.04);
        }
        let spots = (wm * hm / 0.004).ceil() as usize;
        for _ in 0..spots {
            let (cx, cy) = (rng.random_range(0.0..wm), rng.random_range(0.0..hm));
            let c = if rng.random_bool(0.5) {
                [110, 80, 40]
            } else {
                [210, 200, 90]
            };
            self.fill_disc(cx, cy, rng.random_range(0.002..0.006), c);
        }
    }

    /// Paints [`Style::Fur`]: shaded tufts, darker flecks, stitched patches.
    fn paint_fur(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64, texel_m: f64) {
        let l: f64 = rng.random_range(90.0..170.0);
        let mut tiles = Vec::new();
        split_tiles(rng, 0.0, 0.0, wm, hm, 0.008, 0.03, &mut |_, x, y, w, h| {
            tiles.push((x, y, w, h))
        });
        for (x, y, w, h) in tiles {
            let k = l + rng.random_range(-30.0..30.0);
            let c = [(k * 1.1).min(255.0) as u8, (k * 0.8) as u8, (k * 0.5) as u8];
            self.fill_rect(x, y, x + w, y + h, c);
        }
        let flecks = (wm * hm / 0.0015).ceil() as usize;
        for _ in 0..flecks {
            let (cx, cy) = (rng.random_range(0.0..wm), rng.random_range(0.0..hm));
            let k = l * rng.random_range(0.3..0.6);
            let c = [(k * 1.1) as u8, (k * 0.8) as u8, (k * 0.5) as u8];
            self.fill_disc(cx, cy, rng.random_range(0.002..0.005), c);
        }
        // Stitched patches (paws, a tummy), seams in dark thread.
        self.scatter(rng, wm, hm, &[(0.05, 0.05)], 0.0, texel_m);
    }

    /// Tiles between `tile.0` and `tile.1` metres of one paint `[luminance, saturation]`,
    /// each shaded by up to +-`contrast` grey levels: walls, carpet, cloth folds.
    fn shaded_patchwork(
        &mut self,
        rng: &mut ChaCha8Rng,
        wm: f64,
        hm: f64,
        tile: (f64, f64),
        paint: [f64; 2],
        contrast: f64,
    ) {
        let hue: [f64; 3] = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let hl = 0.299 * hue[0] + 0.587 * hue[1] + 0.114 * hue[2];
        let mut tiles = Vec::new();
        split_tiles(
            rng,
            0.0,
            0.0,
            wm,
            hm,
            tile.0,
            tile.1,
            &mut |_, x, y, w, h| tiles.push((x, y, w, h)),
        );
        for (x, y, w, h) in tiles {
            let lum = paint[0] + rng.random_range(-contrast..=contrast);
            let amp = paint[1] * lum.min(255.0 - lum).max(20.0);
            let c = |i: usize| (lum + amp * (hue[i] - hl)).clamp(0.0, 255.0) as u8;
            self.fill_rect(x, y, x + w, y + h, [c(0), c(1), c(2)]);
        }
    }

    /// Copies `other` onto this texture with its corner at (`x0`, `y0`) metres (same texel
    /// size; wraps).
    fn blit(&mut self, other: &Texture, x0: f64, y0: f64) {
        let ox = (x0 * self.scale).round() as i64;
        let oy = (y0 * self.scale).round() as i64;
        for j in 0..other.h {
            for i in 0..other.w {
                self.put(ox + i as i64, oy + j as i64, other.data[j * other.w + i]);
            }
        }
    }

    /// A texture of `width_m` x `height_m` metres at `texels_per_m`, texel (i, j) coloured
    /// `f(s, t)` at its centre (s, t in metres): test patterns and calibration targets.
    pub fn from_fn(
        width_m: f64,
        height_m: f64,
        texels_per_m: f64,
        f: impl Fn(f64, f64) -> [u8; 3],
    ) -> Texture {
        let w = ((width_m * texels_per_m).round() as usize).max(1);
        let h = ((height_m * texels_per_m).round() as usize).max(1);
        let scale = w as f64 / width_m;
        let mut data = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                data.push(f((i as f64 + 0.5) / scale, (j as f64 + 0.5) / scale));
            }
        }
        Texture { w, h, scale, data }
    }

    /// Width and height in metres.
    pub fn size_m(&self) -> (f64, f64) {
        (self.w as f64 / self.scale, self.h as f64 / self.scale)
    }

    /// Bilinear colour (0..255 floats) at surface coordinates (s, t) in metres; wraps around.
    #[inline]
    pub fn sample(&self, s: f64, t: f64) -> [f32; 3] {
        let x = s * self.scale - 0.5;
        let y = t * self.scale - 0.5;
        let xf = floor(x);
        let yf = floor(y);
        let fx = (x - xf) as f32;
        let fy = (y - yf) as f32;
        let x0 = wrap(xf as i64, self.w);
        let y0 = wrap(yf as i64, self.h);
        let x1 = if x0 + 1 == self.w { 0 } else { x0 + 1 };
        let y1 = if y0 + 1 == self.h { 0 } else { y0 + 1 };
        let a = self.data[y0 * self.w + x0];
        let b = self.data[y0 * self.w + x1];
        let c = self.data[y1 * self.w + x0];
        let d = self.data[y1 * self.w + x1];
        let mut out = [0.0f32; 3];
        for i in 0..3 {
            let top = a[i] as f32 + (b[i] as f32 - a[i] as f32) * fx;
            let bot = c[i] as f32 + (d[i] as f32 - c[i] as f32) * fx;
            out[i] = top + (bot - top) * fy;
        }
        out
    }

    /// Recursive random split of a rectangle into tiles between `min` and `max` metres wide,
    /// each a random colour: a non-periodic "checker".
    #[allow(clippy::too_many_arguments)]
    fn patchwork(
        &mut self,
        rng: &mut ChaCha8Rng,
        x: f64,
        y: f64,
        w: f64,
        h: f64,
        min: f64,
        max: f64,
    ) {
        split_tiles(rng, x, y, w, h, min, max, &mut |rng, x, y, w, h| {
            let c = random_colour(rng);
            self.fill_rect(x, y, x + w, y + h, c);
        });
    }

    /// Wood-like streaks: thin random horizontal bands of nearby brown tones.
    fn streaks(&mut self, rng: &mut ChaCha8Rng, wm: f64, hm: f64) {
        let mut y = 0.0;
        while y < hm {
            let th = rng.random_range(0.004..0.03);
            let l: f64 = rng.random_range(90.0..170.0);
            let c = [
                (l * 1.25).min(255.0) as u8,
                (l * 0.95) as u8,
                (l * 0.6) as u8,
            ];
            self.fill_rect(0.0, y, wm, y + th, c);
            y += th;
        }
    }

    /// Random shapes at the given (scale, coverage) pairs (metres, large first; coverage is the
    /// painted area as a fraction of the surface); `text` is the share of glyph blocks among
    /// shapes large enough to carry legible glyphs (5 texels high).
    fn scatter(
        &mut self,
        rng: &mut ChaCha8Rng,
        wm: f64,
        hm: f64,
        scales: &[(f64, f64)],
        text: f64,
        texel: f64,
    ) {
        for &(s, coverage) in scales {
            let n = (coverage * wm * hm / (s * s)).ceil() as usize;
            let text = if s * 0.08 >= 5.0 * texel { text } else { 0.0 };
            for _ in 0..n {
                let size = s * rng.random_range(0.6..1.6);
                let cx = rng.random_range(0.0..wm);
                let cy = rng.random_range(0.0..hm);
                let colour = random_colour(rng);
                let kind = if rng.random_bool(text) {
                    4
                } else {
                    rng.random_range(0..4)
                };
                match kind {
                    0 | 1 => {
                        // Rectangle, axis-aligned half the time, otherwise rotated.
                        let a = if kind == 0 {
                            0.0
                        } else {
                            rng.random_range(0.0..std::f64::consts::PI)
                        };
                        let ar = rng.random_range(0.3..1.0);
                        let (hw, hh) = (size * 0.5, size * 0.5 * ar);
                        let (ca, sa) = (a.cos(), a.sin());
                        let p = |x: f64, y: f64| (cx + ca * x - sa * y, cy + sa * x + ca * y);
                        if kind == 0 {
                            self.fill_rect(cx - hw, cy - hh, cx + hw, cy + hh, colour);
                        } else {
                            self.fill_polygon(
                                &[p(-hw, -hh), p(hw, -hh), p(hw, hh), p(-hw, hh)],
                                colour,
                            );
                        }
                    }
                    2 => {
                        let mut pts = [(0.0, 0.0); 3];
                        let a0 = rng.random_range(0.0..std::f64::consts::TAU);
                        for (i, q) in pts.iter_mut().enumerate() {
                            let a = a0 + i as f64 * 2.1 + rng.random_range(-0.4..0.4);
                            let r = size * rng.random_range(0.35..0.6);
                            *q = (cx + r * a.cos(), cy + r * a.sin());
                        }
                        self.fill_polygon(&pts, colour);
                    }
                    3 => self.fill_disc(cx, cy, size * 0.4, colour),
                    _ => self.text_block(rng, cx, cy, size, 5.0 * texel),
                }
            }
        }
    }

    /// A light "paper" with lines of random blocky glyphs (3x5 cells) in a dark ink.
    fn text_block(&mut self, rng: &mut ChaCha8Rng, x0: f64, y0: f64, size: f64, min_h: f64) {
        let glyph_h = (size * rng.random_range(0.08..0.16)).max(min_h);
        let glyph_w = glyph_h * 0.6;
        let cols = rng.random_range(6..18);
        let lines = rng.random_range(2..7);
        let pw = cols as f64 * glyph_w * 1.3 + glyph_w;
        let ph = lines as f64 * glyph_h * 1.6 + glyph_h;
        let paper = [
            rng.random_range(215..=255),
            rng.random_range(215..=255),
            rng.random_range(200..=250),
        ];
        self.fill_rect(x0, y0, x0 + pw, y0 + ph, paper);
        let ink_l: f64 = rng.random_range(10.0..70.0);
        let ink = [
            ink_l as u8,
            (ink_l * 0.9) as u8,
            (ink_l * 1.3).min(255.0) as u8,
        ];
        let cw = glyph_w / 3.0;
        let ch = glyph_h / 5.0;
        for line in 0..lines {
            let gy = y0 + glyph_h * 0.5 + line as f64 * glyph_h * 1.6;
            let len = rng.random_range(cols / 2..=cols);
            for col in 0..len {
                if rng.random_bool(0.15) {
                    continue; // word gap
                }
                let gx = x0 + glyph_w * 0.5 + col as f64 * glyph_w * 1.3;
                let mut bits: u16 = rng.random_range(1..(1 << 15));
                if bits.count_ones() < 4 {
                    bits |= 0b010_010_010_010_010;
                }
                for k in 0..15 {
                    if bits & (1 << k) != 0 {
                        let (cx, cy) = ((k % 3) as f64, (k / 3) as f64);
                        let (ax, ay) = (gx + cx * cw, gy + cy * ch);
                        self.fill_rect(ax, ay, ax + cw, ay + ch, ink);
                    }
                }
            }
        }
    }

    /// Fills the axis-aligned rectangle [x0, x1) x [y0, y1) given in metres (wraps).
    fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, c: [u8; 3]) {
        let s = self.scale;
        let (tx0, tx1) = ((x0 * s - 0.5).ceil() as i64, (x1 * s - 0.5).ceil() as i64);
        let (ty0, ty1) = ((y0 * s - 0.5).ceil() as i64, (y1 * s - 0.5).ceil() as i64);
        if tx0 >= tx1 {
            return;
        }
        let x_start = wrap(tx0, self.w);
        for ty in ty0..ty1 {
            let row = wrap(ty, self.h) * self.w;
            // Texels tx0..tx1 from column x_start on, wrapping at the right edge.
            let mut x = x_start;
            for _ in tx0..tx1 {
                self.data[row + x] = c;
                x += 1;
                if x == self.w {
                    x = 0;
                }
            }
        }
    }

    /// Fills a convex polygon (at most 4 vertices) given in metres (texel centres inside are
    /// painted; wraps).
    fn fill_polygon(&mut self, pts: &[(f64, f64)], c: [u8; 3]) {
        let s = self.scale;
        let mut buf = [(0.0, 0.0); 4];
        let n = pts.len().min(4);
        for (b, &(x, y)) in buf.iter_mut().zip(pts) {
            *b = (x * s, y * s);
        }
        let p = &buf[..n];
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in p {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        // Orientation so that "inside" is the same sign for every edge.
        let mut area = 0.0;
        for i in 0..n {
            let (a, b) = (p[i], p[(i + 1) % n]);
            area += a.0 * b.1 - b.0 * a.1;
        }
        let sign = if area >= 0.0 { 1.0 } else { -1.0 };
        // Edge i from a to b: the texel centre (px, py) is inside when
        // sign * ((b.0 - a.0) * (py - a.1) - (b.1 - a.1) * (px - a.0)) >= 0 for every edge.
        // Per edge: (a.0, b.1 - a.1) and, per row, (b.0 - a.0) * (py - a.1): the same
        // operations on the same values as evaluating the whole expression per texel.
        let mut edges = [(0.0, 0.0, 0.0, 0.0); 4];
        for (i, e) in edges.iter_mut().enumerate().take(n) {
            let (a, b) = (p[i], p[(i + 1) % n]);
            *e = (a.0, a.1, b.0 - a.0, b.1 - a.1);
        }
        let edges = &edges[..n];
        let (tx0, tx1) = (x0.floor() as i64, x1.ceil() as i64);
        for ty in (y0.floor() as i64)..=(y1.ceil() as i64) {
            let py = ty as f64 + 0.5;
            let mut row = [0.0; 4];
            for (r, e) in row.iter_mut().zip(edges) {
                *r = e.2 * (py - e.1);
            }
            let row = &row[..n];
            let y = wrap(ty, self.h) * self.w;
            let mut x = wrap(tx0, self.w);
            for tx in tx0..=tx1 {
                let px = tx as f64 + 0.5;
                let inside = edges
                    .iter()
                    .zip(row)
                    .all(|(e, r)| sign * (r - e.3 * (px - e.0)) >= 0.0);
                if inside {
                    self.data[y + x] = c;
                }
                x += 1;
                if x == self.w {
                    x = 0;
                }
            }
        }
    }

    /// Fills a disc of radius `r` metres centred at (cx, cy) metres.
    fn fill_disc(&mut self, cx: f64, cy: f64, r: f64, c: [u8; 3]) {
        let s = self.scale;
        let (cx, cy, r) = (cx * s, cy * s, r * s);
        for ty in ((cy - r).floor() as i64)..=((cy + r).ceil() as i64) {
            for tx in ((cx - r).floor() as i64)..=((cx + r).ceil() as i64) {
                let (dx, dy) = (tx as f64 + 0.5 - cx, ty as f64 + 0.5 - cy);
                if dx * dx + dy * dy <= r * r {
                    self.put(tx, ty, c);
                }
            }
        }
    }

    #[inline]
    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        let x = wrap(x, self.w);
        let y = wrap(y, self.h);
        self.data[y * self.w + x] = c;
    }
}

/// `x.floor()` for the texture coordinates of [`Texture::sample`] (|x| < 2^52), inline:
/// `f64::floor` is a libm call on baseline x86-64. (-0.0 gives 0.0, which changes no sample:
/// only the sign of a zero interpolation weight.)
#[inline]
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// `i` wrapped into 0..n (`i.rem_euclid(n)`), without the division when it is already there.
#[inline]
fn wrap(i: i64, n: usize) -> usize {
    if (i as u64) < n as u64 {
        i as usize
    } else {
        i.rem_euclid(n as i64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// How many of the 10 cm x 10 cm patches of a `side` m texture have more than 60 grey
    /// levels of contrast.
    fn rich_patches(t: &Texture, side: usize) -> usize {
        let mut rich = 0;
        for by in 0..side * 10 {
            for bx in 0..side * 10 {
                let (mut lo, mut hi) = (255.0f32, 0.0f32);
                for j in 0..25 {
                    for i in 0..25 {
                        let c = t.sample(
                            bx as f64 * 0.1 + i as f64 * 0.004,
                            by as f64 * 0.1 + j as f64 * 0.004,
                        );
                        let l = 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2];
                        lo = lo.min(l);
                        hi = hi.max(l);
                    }
                }
                rich += (hi - lo > 60.0) as usize;
            }
        }
        rich
    }

    #[test]
    fn collage_has_contrast_everywhere() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let t = Texture::collage(&mut rng, 1.0, 1.0, 0.004, Style::Poster);
        // Nearly every 10 cm x 10 cm patch has at least 60 grey levels of contrast.
        let rich = rich_patches(&t, 1);
        assert!(rich >= 85, "{rich} of 100 patches have contrast");
    }

    #[test]
    fn office_walls_and_floors_are_mostly_plain() {
        for seed in 0..3 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let wall = Texture::collage(&mut rng, 3.0, 3.0, 0.004, Style::OfficeWall);
            let rich = rich_patches(&wall, 3);
            // Posters on ~12 % of the wall (their frames add a little): some structure, mostly
            // plain paint.
            assert!((20..=250).contains(&rich), "wall: {rich} of 900 patches");
            let floor = Texture::collage(&mut rng, 3.0, 3.0, 0.004, Style::OfficeFloor);
            assert_eq!(
                rich_patches(&floor, 3),
                0,
                "carpet tiles differ by a few levels"
            );
        }
    }

    #[test]
    fn bilinear_sample_interpolates_between_texels() {
        let mut t = Texture {
            w: 2,
            h: 1,
            scale: 1.0,
            data: vec![[0, 0, 0], [200, 100, 50]],
        };
        assert_eq!(t.sample(0.5, 0.5), [0.0, 0.0, 0.0]);
        assert_eq!(t.sample(1.0, 0.5), [100.0, 50.0, 25.0]);
        t.put(-1, 0, [10, 10, 10]);
        assert_eq!(t.data[1], [10, 10, 10]);
    }
}
