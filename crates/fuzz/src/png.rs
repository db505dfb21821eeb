//! A small PNG writer for the image readers' seeds: every colour type and bit depth the format
//! has (grey at 1, 2, 4, 8 and 16 bits, grey+alpha, RGB and RGBA at 8 and 16, palettes at 1,
//! 2, 4 and 8 bits, transparency keys), Adam7 interlacing, each of the five row filters, and
//! files cut short — the PNGs the `image` crate's encoder does not write. The compressed data
//! is deflate's stored blocks (no compression), so the files are small only because the
//! images are; `seeds/png-*.png` are its output ([`seeds`]), checked by the fuzz crate's tests.

use datasets::decode::png_crc32;

/// PNG colour types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colour {
    /// Grey (1 sample).
    Grey = 0,
    /// RGB (3 samples).
    Rgb = 2,
    /// Palette index (1 sample).
    Palette = 3,
    /// Grey and alpha (2 samples).
    GreyAlpha = 4,
    /// RGBA (4 samples).
    Rgba = 6,
}

impl Colour {
    /// Samples per pixel.
    pub fn channels(self) -> usize {
        match self {
            Colour::Grey | Colour::Palette => 1,
            Colour::GreyAlpha => 2,
            Colour::Rgb => 3,
            Colour::Rgba => 4,
        }
    }
}

/// An image to write: its samples row by row (`channels` a pixel, each below 2^bit_depth).
#[derive(Clone, Debug)]
pub struct Image {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Colour type.
    pub colour: Colour,
    /// Bits a sample: 1, 2, 4, 8 or 16 as the colour type allows.
    pub bit_depth: u8,
    /// Adam7 interlacing.
    pub interlaced: bool,
    /// The palette (`PLTE`), RGB.
    pub palette: Vec<[u8; 3]>,
    /// The `tRNS` chunk's data, if any (palette alphas, or the transparent grey / RGB).
    pub trns: Option<Vec<u8>>,
    /// Samples, `width * height * channels`, row-major.
    pub samples: Vec<u16>,
}

/// Adam7's passes: first column, first row, column step, row step.
const ADAM7: [(usize, usize, usize, usize); 7] = [
    (0, 0, 8, 8),
    (4, 0, 8, 8),
    (0, 4, 4, 8),
    (2, 0, 4, 4),
    (0, 2, 2, 4),
    (1, 0, 2, 2),
    (0, 1, 1, 2),
];

fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let p = i16::from(a) + i16::from(b) - i16::from(c);
    let (pa, pb, pc) = (
        (p - i16::from(a)).abs(),
        (p - i16::from(b)).abs(),
        (p - i16::from(c)).abs(),
    );
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}

impl Image {
    /// The packed bytes of one row of the pixels at columns `xs` of row `y`.
    fn row_bytes(&self, y: usize, xs: &[usize]) -> Vec<u8> {
        let ch = self.colour.channels();
        let mut out = Vec::new();
        let (mut acc, mut bits) = (0u16, 0u8);
        for &x in xs {
            for c in 0..ch {
                let v = self.samples[(y * self.width + x) * ch + c];
                match self.bit_depth {
                    16 => out.extend_from_slice(&v.to_be_bytes()),
                    8 => out.push(v as u8),
                    d => {
                        acc = (acc << d) | v;
                        bits += d;
                        if bits == 8 {
                            out.push(acc as u8);
                            (acc, bits) = (0, 0);
                        }
                    }
                }
            }
        }
        if bits > 0 {
            out.push((acc << (8 - bits)) as u8);
        }
        out
    }

    /// The filtered scanlines (a filter byte, then the row), filters taken in turn so that
    /// every one of the five is used.
    fn scanlines(&self) -> Vec<u8> {
        let bpp = (self.colour.channels() * usize::from(self.bit_depth)).div_ceil(8);
        let passes: Vec<(usize, usize, usize, usize)> = if self.interlaced {
            ADAM7.to_vec()
        } else {
            vec![(0, 0, 1, 1)]
        };
        let mut out = Vec::new();
        let mut filter = 0u8;
        for (x0, y0, dx, dy) in passes {
            let xs: Vec<usize> = (x0..self.width).step_by(dx).collect();
            if xs.is_empty() {
                continue;
            }
            let mut prev: Vec<u8> = Vec::new();
            for y in (y0..self.height).step_by(dy) {
                let row = self.row_bytes(y, &xs);
                if prev.is_empty() {
                    prev = vec![0; row.len()];
                }
                out.push(filter);
                for i in 0..row.len() {
                    let a = if i >= bpp { row[i - bpp] } else { 0 };
                    let b = prev[i];
                    let c = if i >= bpp { prev[i - bpp] } else { 0 };
                    let predicted = match filter {
                        0 => 0,
                        1 => a,
                        2 => b,
                        3 => ((u16::from(a) + u16::from(b)) / 2) as u8,
                        _ => paeth(a, b, c),
                    };
                    out.push(row[i].wrapping_sub(predicted));
                }
                prev = row;
                filter = (filter + 1) % 5;
            }
        }
        out
    }

    /// The whole file.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&(self.width as u32).to_be_bytes());
        ihdr.extend_from_slice(&(self.height as u32).to_be_bytes());
        ihdr.extend_from_slice(&[
            self.bit_depth,
            self.colour as u8,
            0,
            0,
            u8::from(self.interlaced),
        ]);
        chunk(&mut out, b"IHDR", &ihdr);
        if !self.palette.is_empty() {
            chunk(&mut out, b"PLTE", &self.palette.concat());
        }
        if let Some(t) = &self.trns {
            chunk(&mut out, b"tRNS", t);
        }
        chunk(&mut out, b"IDAT", &zlib_stored(&self.scanlines()));
        chunk(&mut out, b"IEND", &[]);
        out
    }
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = png_crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// `data` as a zlib stream of stored (uncompressed) deflate blocks.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = if data.is_empty() {
        vec![&[]]
    } else {
        data.chunks(65_535).collect()
    };
    for (i, b) in blocks.iter().enumerate() {
        out.push(u8::from(i + 1 == blocks.len()));
        let len = b.len() as u16;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(b);
    }
    let (mut a, mut s) = (1u32, 0u32);
    for &x in data {
        a = (a + u32::from(x)) % 65_521;
        s = (s + a) % 65_521;
    }
    out.extend_from_slice(&((s << 16) | a).to_be_bytes());
    out
}

/// An image whose samples run through `levels` values (at most 2^bit_depth) over (x, y,
/// channel), spread over the whole range for the 16-bit ones.
fn pattern(
    width: usize,
    height: usize,
    colour: Colour,
    bit_depth: u8,
    interlaced: bool,
    levels: usize,
) -> Image {
    let ch = colour.channels();
    let spread = if levels > 256 { 997 } else { 1 };
    let samples = (0..width * height * ch)
        .map(|k| {
            let (p, c) = (k / ch, k % ch);
            let (x, y) = (p % width, p / width);
            ((x * 7 + y * 13 + c * 5) * spread % levels) as u16
        })
        .collect();
    Image {
        width,
        height,
        colour,
        bit_depth,
        interlaced,
        palette: Vec::new(),
        trns: None,
        samples,
    }
}

/// A palette of `n` colours spread over the RGB cube.
fn palette(n: usize) -> Vec<[u8; 3]> {
    (0..n)
        .map(|i| {
            let i = i as u32;
            [
                (i * 37 % 256) as u8,
                (i * 101 % 256) as u8,
                (255 - i * 53 % 256) as u8,
            ]
        })
        .collect()
}

/// What a seed is, and what a reader must make of it.
#[derive(Clone, Debug)]
pub struct Seed {
    /// File name under `seeds/`.
    pub name: &'static str,
    /// The image written, before any cut.
    pub image: Image,
    /// The file's bytes (cut short for the truncated seeds).
    pub bytes: Vec<u8>,
    /// Whether the file was cut inside its image data (a reader may refuse it).
    pub cut: bool,
}

/// Every PNG seed: the pixel formats and layouts the `image` crate's encoder does not write,
/// interlaced ones, and files cut short.
pub fn seeds() -> Vec<Seed> {
    let (w, h) = (13, 7);
    let mut out = Vec::new();
    let mut add = |name: &'static str, image: Image| {
        let bytes = image.encode();
        out.push(Seed {
            name,
            image,
            bytes,
            cut: false,
        });
    };
    add("png-grey1.png", pattern(w, h, Colour::Grey, 1, false, 2));
    add(
        "png-grey2-adam7.png",
        pattern(w, h, Colour::Grey, 2, true, 4),
    );
    add("png-grey4.png", pattern(w, h, Colour::Grey, 4, false, 16));
    // Three pixels wide, one high: Adam7 passes with no pixel at all.
    add(
        "png-grey4-adam7-3x1.png",
        pattern(3, 1, Colour::Grey, 4, true, 16),
    );
    let mut key = pattern(w, h, Colour::Grey, 8, false, 256);
    key.trns = Some(vec![0, 20]);
    add("png-grey8-trns.png", key);
    add(
        "png-greyalpha8.png",
        pattern(w, h, Colour::GreyAlpha, 8, false, 256),
    );
    add(
        "png-greyalpha16-adam7.png",
        pattern(w, h, Colour::GreyAlpha, 16, true, 65_536),
    );
    add(
        "png-rgb16.png",
        pattern(w, h, Colour::Rgb, 16, false, 65_536),
    );
    add(
        "png-rgba16-adam7.png",
        pattern(w, h, Colour::Rgba, 16, true, 65_536),
    );
    add(
        "png-depth16-adam7.png",
        pattern(w, h, Colour::Grey, 16, true, 65_536),
    );
    for (name, depth, colours, trns, interlaced) in [
        ("png-palette1.png", 1u8, 2usize, false, false),
        ("png-palette2-adam7.png", 2, 4, false, true),
        ("png-palette4-trns.png", 4, 11, true, false),
        ("png-palette8.png", 8, 200, false, false),
    ] {
        let mut p = pattern(w, h, Colour::Palette, depth, interlaced, colours);
        p.palette = palette(colours);
        if trns {
            p.trns = Some((0..colours).map(|i| (i * 23) as u8).collect());
        }
        add(name, p);
    }
    // Indices past the end of a three-colour palette.
    let mut past = pattern(w, h, Colour::Palette, 4, false, 16);
    past.palette = palette(3);
    add("png-palette4-past-the-end.png", past);
    // Cut short: inside the image data, and after it (no IEND).
    let depth = pattern(w, h, Colour::Grey, 16, false, 65_536);
    let whole = depth.encode();
    out.push(Seed {
        name: "png-depth16-cut-in-idat.png",
        bytes: whole[..whole.len() / 2].to_vec(),
        image: depth,
        cut: true,
    });
    let rgb = pattern(w, h, Colour::Rgb, 8, false, 256);
    let whole = rgb.encode();
    out.push(Seed {
        name: "png-rgb8-no-iend.png",
        bytes: whole[..whole.len() - 12].to_vec(),
        image: rgb,
        cut: false,
    });
    out
}
