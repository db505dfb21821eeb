//! The PNG seeds of `seeds/` (written by `fuzz::png`: palettes, 1/2/4-bit grey, grey+alpha,
//! 16-bit RGB(A), Adam7, files cut short): the committed files are the writer's output
//! (`FUZZ_WRITE_SEEDS=1 cargo test -p fuzz --test integration image_seeds` writes them again), and every
//! image reader accepts each with the pixels it holds or refuses it with an error naming the
//! file.

use datasets::decode::{read_depth, read_gray, read_image, rgb_to_gray};
use fuzz::png::{Colour, Image};
use std::path::{Path, PathBuf};

fn seeds_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds")
}

#[test]
fn the_committed_png_seeds_are_the_writers() {
    let write = std::env::var_os("FUZZ_WRITE_SEEDS").is_some();
    let seeds = fuzz::png::seeds();
    let mut total = 0;
    for s in &seeds {
        let p = seeds_dir().join(s.name);
        if write {
            std::fs::write(&p, &s.bytes).unwrap();
        }
        assert!(
            std::fs::read(&p).ok().as_ref() == Some(&s.bytes),
            "{} is not fuzz::png's; FUZZ_WRITE_SEEDS=1 cargo test -p fuzz --test integration image_seeds \
             writes it",
            s.name
        );
        total += s.bytes.len();
    }
    assert!(
        seeds.len() >= 16 && total < 16 << 10,
        "{} seeds, {total} bytes",
        seeds.len()
    );
}

/// Each pixel's 8-bit RGB, what an 8-bit conversion of the image gives: low-bit grey scaled to
/// 0..=255, 16-bit samples rounded (v + 128) / 257, palette entries looked up (`None` past the
/// palette's end).
fn rgb8(img: &Image) -> Vec<Option<[u8; 3]>> {
    let ch = img.colour.channels();
    let to8 = |v: u16| -> u8 {
        match img.bit_depth {
            16 => ((u32::from(v) + 128) / 257) as u8,
            8 => v as u8,
            d => (u32::from(v) * 255 / ((1 << d) - 1)) as u8,
        }
    };
    (0..img.width * img.height)
        .map(|p| {
            let s = &img.samples[p * ch..(p + 1) * ch];
            match img.colour {
                Colour::Grey | Colour::GreyAlpha => Some([to8(s[0]); 3]),
                Colour::Rgb | Colour::Rgba => Some([to8(s[0]), to8(s[1]), to8(s[2])]),
                Colour::Palette => img.palette.get(usize::from(s[0])).copied(),
            }
        })
        .collect()
}

/// `got` (one value a pixel) agrees with `want` wherever `want` is known.
fn same<T: PartialEq + std::fmt::Debug>(name: &str, got: &[T], want: &[Option<T>]) {
    assert_eq!(got.len(), want.len(), "{name}: pixel count");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        if let Some(w) = w {
            assert_eq!(g, w, "{name}: pixel {k}");
        }
    }
}

#[test]
fn every_image_reader_reads_each_png_seed_right_or_refuses_it_by_name() {
    let dir = std::env::temp_dir().join(format!("nf-fuzz-png-seeds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut accepted, mut refused) = (0, 0);
    for s in fuzz::png::seeds() {
        let path = dir.join(s.name);
        std::fs::write(&path, &s.bytes).unwrap();
        let img = &s.image;
        let want = rgb8(img);
        let mut names = |e: &dyn std::fmt::Display| {
            let e = e.to_string();
            assert!(
                e.contains(s.name),
                "{}: error without the file: {e}",
                s.name
            );
            refused += 1;
        };
        // Grey, as the sequences read colour and grey images.
        match read_gray(&path) {
            Ok(g) => {
                assert_eq!((g.width, g.height), (img.width, img.height), "{}", s.name);
                let want: Vec<Option<u8>> = want
                    .iter()
                    .map(|p| p.map(|[r, g, b]| rgb_to_gray(r, g, b)))
                    .collect();
                same(s.name, &g.data, &want);
                accepted += 1;
            }
            Err(e) => names(&e),
        }
        // Depth: a 16-bit grey PNG without transparency, in metres; anything else refused.
        let depth = img.colour == Colour::Grey && img.bit_depth == 16 && img.trns.is_none();
        match read_depth(&path, 5000.0) {
            Ok(d) => {
                assert!(depth, "{}: read as depth", s.name);
                let want: Vec<Option<f32>> = img
                    .samples
                    .iter()
                    .map(|&v| Some((f64::from(v) / 5000.0) as f32))
                    .collect();
                same(s.name, &d.data, &want);
                accepted += 1;
            }
            Err(e) => {
                assert!(!depth || s.cut, "{}: {e}", s.name);
                names(&e)
            }
        }
        // Any image, as `noisefree features` reads it.
        match read_image(&path) {
            Ok(i) => {
                assert_eq!(
                    (i.width() as usize, i.height() as usize),
                    (img.width, img.height)
                );
                let got: Vec<[u8; 3]> = i.to_rgb8().pixels().map(|p| p.0).collect();
                same(s.name, &got, &want);
                accepted += 1;
            }
            Err(e) => names(&e),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        accepted > 30 && refused > 5,
        "{accepted} accepted, {refused} refused"
    );
}
