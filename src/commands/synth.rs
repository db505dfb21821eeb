//! `noisefree synth`: writes a synthetic sequence (TUM RGB-D layout, or EuRoC ASL for the
//! stereo preset) with exact ground truth, and optionally a contact-sheet PNG of it.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};

/// Arguments of `noisefree synth`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Presets (easy to hard): clean, kinect, boundary, walking, stereo, \
distorted, lag, hard, occluded, loop.\nThe same preset, seed and frame count always give the same \
bytes."
)]
pub struct SynthArgs {
    /// Preset, named after the effect it models: clean (no noise), kinect (axial, quantisation,
    /// lateral, holes), boundary (strong lateral mixing, misregistration), walking (kinect and
    /// moving people), stereo (EuRoC-like pair, no depth), distorted (4 % depth scale + radial
    /// wobble), lag (2-frame depth lag, fast motion), hard (walking + distorted + lag),
    /// occluded (lens covered for frames 120..150), loop (a 40 s circuit round the room back to
    /// its start and 15 s past it, with a depth error that makes odometry drift: for loop
    /// closing).
    #[arg(long, default_value = "kinect")]
    pub preset: String,
    /// Number of frames to write (30 Hz, so 300 frames = 10 s). Default: the preset's, 300
    /// (1650 for loop: its circuit plus 15 s of revisit).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Seed of the scene textures and of every noise draw: the sequence that `run --seq P
    /// --synth-seed S` runs on (both default to 0, so `synth` and `run` give the same sequence).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output folder; must not exist or be empty (see --force). RGB-D presets write the TUM
    /// RGB-D layout (rgb/, depth/, rgb.txt, depth.txt, groundtruth.txt, associations.txt);
    /// `stereo` writes the EuRoC ASL layout (mav0/cam0, cam1, state_groundtruth_estimate0).
    #[arg(long)]
    pub out: PathBuf,
    /// Camera trajectory overriding the preset's: xyz (handheld translation, default), rpy
    /// (rotation-heavy), spin (360 degrees in 20 s), loop (a closed 40 s circuit round the room
    /// looking at the walls, back to its start pose, then on round again), or the path of a
    /// TUM trajectory file (`stamp tx ty tz qx qy qz qw`, camera-to-world, as TUM ground
    /// truth): it is levelled (mean camera y axis = down), centred in the room at 1.3 m height
    /// and replayed in its own time (interpolated); never scaled, so a path larger than the
    /// room (4 x 4 x 1.7 m usable) or shorter than the frames asked for is refused.
    #[arg(long, value_name = "NAME|FILE")]
    pub trajectory: Option<String>,
    /// Cover the lens with a flat featureless surface 0.5 m away for frames START..START+LEN,
    /// given as START:LEN (frames), e.g. 120:30.
    #[arg(long, value_name = "START:LEN")]
    pub occlusion: Option<String>,
    /// Also write a contact sheet PNG (colour | depth colour-mapped 0.4-5 m | depth error +-5 cm;
    /// stereo: left | right | true depth) of 4 frames spread over the sequence.
    #[arg(long, value_name = "FILE.png")]
    pub contact_sheet: Option<PathBuf>,
    /// Effects to switch off, comma-separated (an ablation): lens, blur,
    /// rolling_shutter, vignetting, auto_exposure, sensor_noise, image_noise, tremor, depth_lag,
    /// axial, quantisation, lateral, holes, misregistration, depth_distortion, mocap_noise,
    /// layout, stamp_jitter, mocap_clock.
    #[arg(long = "synth-without", value_name = "EFFECTS", value_delimiter = ',')]
    pub synth_without: Vec<String>,
    /// Remove the output folder first if it exists and is not empty.
    #[arg(long)]
    pub force: bool,
}

fn parse_occlusion(s: &str) -> anyhow::Result<(usize, usize)> {
    let (a, b) = s
        .split_once(':')
        .with_context(|| format!("--occlusion '{s}': expected START:LEN"))?;
    Ok((
        a.trim()
            .parse()
            .with_context(|| format!("--occlusion start '{a}'"))?,
        b.trim()
            .parse()
            .with_context(|| format!("--occlusion length '{b}'"))?,
    ))
}

/// Runs `noisefree synth`.
pub fn run(args: SynthArgs) -> anyhow::Result<()> {
    let preset = synth::Preset::from_name(&args.preset)?;
    let mut config = preset.config();
    if let Some(t) = &args.trajectory {
        config.trajectory = synth::Trajectory::from_arg(t)?;
        if let synth::Trajectory::Recorded(path) = &config.trajectory {
            if let Some(w) = path.warning() {
                eprintln!("warning: {w}");
            }
        }
    }
    if let Some(o) = &args.occlusion {
        config.occlusion = Some(parse_occlusion(o)?);
    }
    for effect in &args.synth_without {
        config.without(effect.trim())?;
    }
    let frames = args.frames.unwrap_or_else(|| preset.default_frames());
    if frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    let gen = synth::Generator::try_new(config, args.seed)?;
    gen.check_frames(frames)?;
    if args.force && args.out.exists() {
        std::fs::remove_dir_all(&args.out)
            .with_context(|| format!("removing {}", args.out.display()))?;
    }
    let pb = ProgressBar::new(frames as u64);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} frames {per_sec} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(format!("synth {}", args.preset));
    let start = Instant::now();
    let progress = |_: usize| pb.inc(1);
    datasets::write::write_synthetic(&gen, frames, &args.out, progress)?;
    pb.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    println!(
        "wrote {} frames of preset '{}' (seed {}, trajectory {}) to {} in {:.1} s ({:.1} frames/s)",
        frames,
        args.preset,
        args.seed,
        gen.config().trajectory.name(),
        args.out.display(),
        secs,
        frames as f64 / secs.max(1e-9)
    );
    if gen.config().is_rgbd() {
        println!(
            "camera: {} (`run --path` reads it; give it to another SLAM system)",
            args.out.join(datasets::FOLDER_SETTINGS).display()
        );
    }
    if let Some(sheet) = &args.contact_sheet {
        synth::write_contact_sheet(&gen, frames, 4, sheet)?;
        println!("wrote contact sheet {}", sheet.display());
    }
    Ok(())
}
