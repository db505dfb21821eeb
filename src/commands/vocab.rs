//! `noisefree vocab`: train a vocabulary of ORB words on images, convert between DBoW2's text
//! form (ORB-SLAM2's `ORBvoc.txt`) and our fast binary form, and describe a vocabulary file.

use crate::vocab_file;
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use slam_core::feature::{Descriptor, OrbConfig, OrbExtractor};
use slam_core::place::{train, TrainParams, Weighting};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Arguments of `noisefree vocab`.
#[derive(clap::Args, Debug)]
pub struct VocabArgs {
    #[command(subcommand)]
    command: VocabCommand,
}

#[derive(clap::Subcommand, Debug)]
enum VocabCommand {
    /// Train a vocabulary (hierarchical k-majority, seeded) on the ORB features of images.
    Train(TrainArgs),
    /// Convert a vocabulary between DBoW2's text form (.txt) and our binary form (any other name).
    Convert(ConvertArgs),
    /// Print a vocabulary's shape (k, L, words, weighting) and how long it took to load.
    Info(InfoArgs),
}

/// Arguments of `noisefree vocab train`.
#[derive(clap::Args, Debug)]
struct TrainArgs {
    /// Image files or folders (searched recursively for .png / .jpg), read in name order.
    #[arg(long = "images", value_name = "DIR", num_args = 1.., required = true)]
    images: Vec<PathBuf>,
    /// Branching factor (ORB-SLAM2: 10).
    #[arg(long, default_value_t = 10)]
    k: usize,
    /// Depth (ORB-SLAM2: 6).
    #[arg(long, default_value_t = 6)]
    levels: usize,
    /// Seed of the k-means++ draws.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Use every N-th image of each --images folder (in name order).
    #[arg(long, default_value_t = 1, value_name = "N")]
    every: usize,
    /// ORB features per image.
    #[arg(long = "n-features", default_value_t = 1000)]
    n_features: usize,
    /// Output file: `.txt` for DBoW2's text form, anything else for the binary form.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    out: PathBuf,
    /// No progress bars.
    #[arg(long)]
    quiet: bool,
}

/// Arguments of `noisefree vocab convert`.
#[derive(clap::Args, Debug)]
struct ConvertArgs {
    /// Vocabulary to read (text or binary, detected from its content).
    input: PathBuf,
    /// Output: `.txt` for DBoW2's text form, anything else for the binary form.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    out: PathBuf,
}

/// Arguments of `noisefree vocab info`.
#[derive(clap::Args, Debug)]
struct InfoArgs {
    /// Vocabulary file (text or binary) [default: the vocabulary compiled into the binary].
    input: Option<PathBuf>,
}

/// Runs `noisefree vocab`.
pub fn run(args: VocabArgs) -> Result<()> {
    match args.command {
        VocabCommand::Train(a) => run_train(a),
        VocabCommand::Convert(a) => {
            let t = Instant::now();
            let voc = vocab_file::read(&a.input)?;
            let read_s = t.elapsed().as_secs_f64();
            vocab_file::write(&a.out, &voc)?;
            println!(
                "{} -> {}: {} words, {} nodes (read in {read_s:.2} s)",
                a.input.display(),
                a.out.display(),
                voc.word_count(),
                voc.node_count()
            );
            Ok(())
        }
        VocabCommand::Info(a) => {
            let t = Instant::now();
            let (name, voc) = match &a.input {
                Some(p) => (p.display().to_string(), vocab_file::read(p)?),
                None => (
                    format!("{} (built in)", vocab_file::DEFAULT_NAME),
                    (*vocab_file::default_vocabulary()).clone(),
                ),
            };
            println!(
                "{}: k {} L {}, {} words, {} nodes, weighting {:?}, scoring L1 (loaded in {:.3} s)",
                name,
                voc.k(),
                voc.levels(),
                voc.word_count(),
                voc.node_count(),
                voc.weighting(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
    }
}

/// Image files under `roots` (files as given, folders searched recursively), sorted by path.
fn image_files(roots: &[PathBuf]) -> Result<Vec<PathBuf>> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
        let entries =
            std::fs::read_dir(dir).with_context(|| format!("reading folder {}", dir.display()))?;
        for e in entries {
            let p = e
                .with_context(|| format!("reading folder {}", dir.display()))?
                .path();
            if p.is_dir() {
                walk(&p, out)?;
            } else if is_image(&p) {
                out.push(p);
            }
        }
        Ok(())
    }
    fn is_image(p: &Path) -> bool {
        p.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| ["png", "jpg", "jpeg"].contains(&e.to_ascii_lowercase().as_str()))
    }
    let mut out = Vec::new();
    for r in roots {
        if r.is_dir() {
            let mut found = Vec::new();
            walk(r, &mut found)?;
            found.sort();
            out.extend(found);
        } else if r.is_file() {
            out.push(r.clone());
        } else {
            bail!("{}: no such image file or folder", r.display());
        }
    }
    Ok(out)
}

fn run_train(a: TrainArgs) -> Result<()> {
    if a.every == 0 {
        bail!("--every must be at least 1");
    }
    if a.k < 2 || a.levels < 1 || a.k > 255 || a.levels > 16 {
        bail!("need 2 <= --k <= 255 and 1 <= --levels <= 16");
    }
    let mut files: Vec<PathBuf> = Vec::new();
    for root in &a.images {
        files.extend(
            image_files(std::slice::from_ref(root))?
                .into_iter()
                .step_by(a.every),
        );
    }
    if files.is_empty() {
        bail!("no .png / .jpg images under {:?}", a.images);
    }
    let bar = |len: u64, what: &str| {
        let b = if a.quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(len)
        };
        b.set_style(
            ProgressStyle::with_template(&format!(
                "{what:>10} [{{bar:40}}] {{pos}}/{{len}} eta {{eta}}"
            ))
            .expect("static template")
            .progress_chars("=> "),
        );
        b
    };
    let t0 = Instant::now();
    let pb = bar(files.len() as u64, "features");
    let cfg = OrbConfig {
        n_features: a.n_features,
        ..OrbConfig::default()
    };
    let images: Vec<Vec<Descriptor>> = files
        .par_iter()
        .map_init(
            || OrbExtractor::new(cfg.clone()),
            |ex, p| -> Result<Vec<Descriptor>> {
                let img = datasets::decode::read_gray(p)?;
                pb.inc(1);
                Ok(ex.extract(&img).1)
            },
        )
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let n: usize = images.iter().map(Vec::len).sum();
    let t_feat = t0.elapsed().as_secs_f64();
    let pb = bar(n as u64, "clustering");
    let done = AtomicUsize::new(0);
    let params = TrainParams {
        k: a.k,
        levels: a.levels,
        weighting: Weighting::TfIdf,
        seed: a.seed,
        ..TrainParams::default()
    };
    let voc = train(&images, &params, &|d| {
        let total = done.fetch_add(d, Ordering::Relaxed) + d;
        pb.set_position(total as u64);
    })
    .map_err(|e| anyhow::anyhow!("training: {e}"))?;
    pb.finish_and_clear();
    vocab_file::write(&a.out, &voc)?;
    println!(
        "trained k {} L {} on {} descriptors of {} images (seed {}): {} words, {} nodes -> {} (features {:.1} s, clustering {:.1} s)",
        a.k,
        a.levels,
        n,
        files.len(),
        a.seed,
        voc.word_count(),
        voc.node_count(),
        a.out.display(),
        t_feat,
        t0.elapsed().as_secs_f64() - t_feat
    );
    Ok(())
}
