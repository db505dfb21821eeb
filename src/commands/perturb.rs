//! `noisefree perturb`: writes a perturbed copy of any sequence (catalogued, synthetic, or a
//! folder) as a TUM RGB-D or EuRoC ASL folder that any SLAM program reads, with the camera as
//! ORB-SLAM2 / ORB-SLAM3 settings beside it, and optionally a contact sheet of four frames
//! (input beside perturbed, titled: [`crate::report::contact_sheet`]).

use super::shared_args::SourceArgs;
use crate::commands::shared_args::SequenceArgs;
use crate::select::open;
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use perturb::{perturb_sequence, Chain, Domain, Family, NamedChain};
use std::path::PathBuf;

/// Arguments of `noisefree perturb`.
#[derive(clap::Args, Debug)]
pub struct PerturbArgs {
    /// The sequence: --seq NAME or --path DIR.
    #[command(flatten)]
    pub source: SourceArgs,
    /// The folder's camera from an ORB-SLAM2 / ORB-SLAM3 settings file.
    #[arg(long, value_name = "FILE.yaml", requires = "path")]
    pub camera: Option<PathBuf>,
    /// The perturbation: `family:level[+family:level...]`, or a named camera chain
    /// `kinect-fr1:1` (see --list).
    #[arg(long, value_name = "CHAIN", required_unless_present = "list")]
    pub perturb: Option<String>,
    /// Seed of the perturbation's random draws.
    #[arg(long = "perturb-seed", default_value_t = 0, value_name = "S")]
    pub perturb_seed: u64,
    /// Output folder (must not exist or be empty).
    #[arg(
        short = 'o',
        long = "out",
        value_name = "DIR",
        required_unless_present = "list"
    )]
    pub out: Option<PathBuf>,
    /// Also write a contact sheet PNG: four frames spread over the sequence, input beside
    /// perturbed (RGB-D: grey and depth of both; stereo: the perturbed right image too), with
    /// column titles, frame numbers, the chain and the depth scale.
    #[arg(long = "contact-sheet", value_name = "FILE.png")]
    pub contact_sheet: Option<PathBuf>,
    /// The sequence's length, synthetic seed and ablated effects, and the data root.
    #[command(flatten)]
    pub sequence: SequenceArgs,
    /// List the perturbation families, their units and valid levels, and exit.
    #[arg(long)]
    pub list: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// The families as a table, then the named camera chains with each member's level and source
/// (for `--list` and the README).
pub fn family_table() -> String {
    let mut s =
        String::from("family                  acts on        unit                  levels\n");
    for f in Family::ALL {
        let (lo, hi, whole) = f.range();
        s.push_str(&format!(
            "{:<23} {:<14} {:<21} {lo} to {hi}{}\n",
            f.name(),
            domain_name(f.domain()),
            f.unit(),
            if whole { ", whole" } else { "" }
        ));
    }
    s.push_str(
        "\nnamed chains (CHAIN:L multiplies every member's level by L: 0 none, 1 the \
         literature's camera, 2 twice as bad):\n",
    );
    for c in NamedChain::ALL {
        s.push_str(&format!(
            "\n{}: {} (levels 0 to {})\n",
            c.name(),
            c.camera(),
            (c.max_level() * 1000.0).floor() / 1000.0
        ));
        for m in c.members() {
            s.push_str(&format!(
                "  {:<23} {:>8} {:<20} {}\n",
                m.family.name(),
                format!("{}", (m.level * 1000.0).round() / 1000.0),
                m.family.unit(),
                m.source.split_whitespace().collect::<Vec<_>>().join(" ")
            ));
        }
    }
    s
}

/// What a family acts on, as `--list` prints it.
fn domain_name(d: Domain) -> &'static str {
    match d {
        Domain::Depth => "depth",
        Domain::Image => "images",
        Domain::Time => "frames, stamps",
        Domain::Dynamic => "scene",
        Domain::Stereo => "stereo rig",
        Domain::Calibration => "given camera",
        Domain::GroundTruth => "ground truth",
    }
}

/// Runs `noisefree perturb`.
pub fn run(args: PerturbArgs) -> Result<()> {
    if args.list {
        print!("{}", family_table());
        return Ok(());
    }
    let chain = Chain::parse(args.perturb.as_deref().unwrap_or("")).context("--perturb")?;
    let out = args.out.clone().context("--out is required")?;
    // Refused before the work starts, as the writer would refuse it at the end.
    datasets::write::files::refuse_occupied(&out)?;
    let source = args.source.source();
    let opts = args.sequence.load_options(args.camera.clone());
    let catalog = datasets::Catalog::embedded();
    let (seq, input) = open(&source, &catalog, &opts)?;
    let (seq, frames) = perturb_sequence(&seq, input.clone(), &chain, args.perturb_seed)
        .with_context(|| format!("--perturb {chain}"))?;
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(frames.len() as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{prefix:>10} [{bar:40}] {pos}/{len} frames, eta {eta}")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_prefix("perturb");
    // The synthetic ablation is named only when there is one (earlier notes had no such line).
    let without = match args.sequence.synth_without.as_slice() {
        [] => String::new(),
        effects => format!("synth_without {}\n", effects.join(",")),
    };
    let note = format!(
        "source {}\nperturbation {}\napplied {}\nperturbation_seed {}\nframes {}\nsynth_seed {}\n{without}written by noisefree {}",
        source.label(),
        args.perturb.as_deref().unwrap_or("none").trim(),
        chain.effective(),
        args.perturb_seed,
        frames.len(),
        args.sequence.synth_seed,
        env!("CARGO_PKG_VERSION")
    );
    // A perturbed ground truth is written from memory, not copied from the source.
    let folder = if chain.touches_groundtruth() {
        None
    } else {
        crate::external::export::source_folder(&source, &catalog, &opts)?
    };
    perturb::write_folder(&seq, &frames, &out, &note, folder.as_deref(), |k| {
        bar.set_position(k as u64)
    })
    .with_context(|| format!("writing {}", out.display()))?;
    bar.finish_and_clear();
    if let Some(sheet) = &args.contact_sheet {
        crate::report::contact_sheet::write(
            &input,
            &frames,
            &perturb_sources(&seq, &chain, args.perturb_seed, input.len())?,
            &format!(
                "{}: {} (perturbation seed {})",
                source.label(),
                chain.effective(),
                args.perturb_seed
            ),
            sheet,
        )?;
    }
    eprintln!(
        "{}: {} frames perturbed by {chain} (seed {}) written to {} (camera: camera-orbslam2.yaml; \
         run it with `noisefree run --path {} --camera {}`)",
        source.label(),
        frames.len(),
        args.perturb_seed,
        out.display(),
        out.display(),
        out.join("camera-orbslam2.yaml").display()
    );
    Ok(())
}

/// For each output frame, the input frame it shows.
fn perturb_sources(
    seq: &datasets::Sequence,
    chain: &Chain,
    seed: u64,
    input_len: usize,
) -> Result<Vec<usize>> {
    let p = perturb::Perturber::new(chain, &seq.camera, 5000.0, seed, input_len, &seq.name)?;
    Ok((0..p.len()).map(|i| p.source(i)).collect())
}
