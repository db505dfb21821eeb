//! `noisefree`: the command line of the workspace. `commands/` holds each subcommand's arguments
//! and a short `run`; the modules beside it do the CLI's own work (plan, run and record a sweep,
//! report its tables and findings, match a difficulty, regress, bench, run external systems);
//! the rest lives in the library crates: `slam-core` (the SLAM system), `ate-eval` (trajectories
//! and ATE), `datasets` (readers, the writer, the catalog), `synth` (synthetic sequences) and
//! `perturb` (perturbations); `fuzz` drives the fuzz targets of the formats read here.

mod analysis;
mod bench;
mod commands;
mod config_file;
mod cpu_time;
mod difficulty;
mod external;
mod file_name;
#[cfg(test)]
mod fuzz_cli;
mod recording;
mod regress;
mod runner;
mod seeded_runs;
mod select;
mod sweep;
mod vocab_file;

use clap::{Parser, Subcommand};
// The results folder and its report are the `results` crate's; these names keep `crate::report`
// and the others where the commands look for them.
use results::{columns, readings, report, suggest};
use std::process::ExitCode;

/// Noise-resilient RGB-D / stereo visual SLAM (ORB-SLAM2 class, with the MC-OR and AVC
/// techniques of "Towards Noise Resilient SLAM") and the tools to evaluate it.
#[derive(Parser, Debug)]
#[command(name = "noisefree", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run SLAM on a sequence (default: the embedded synthetic sequence) and report its ATE.
    Run(commands::run::RunArgs),
    /// Sweep sequences x configurations x parameter grids x n seeds in parallel (resumable, shardable).
    Sweep(Box<commands::sweep::SweepArgs>),
    /// Turn sweep records into the paper's tables (Markdown + CSV).
    Table(commands::table::TableArgs),
    /// The findings: each claim of the paper against the committed tables, with intervals.
    Report(commands::report::ReportArgs),
    /// The paper's analyses of MC-OR and AVC (Table II correlations, Fig. 7 / Fig. 8).
    Analyze(commands::analyze::AnalyzeArgs),
    /// ATE / RPE of an estimated trajectory against ground truth (like evo_ape / evaluate_ate.py).
    Eval(commands::eval::EvalArgs),
    /// Top view of estimated trajectories aligned to and drawn over the ground truth (PNG + SVG).
    Plot(commands::plot::PlotArgs),
    /// Generate a synthetic RGB-D or stereo sequence (TUM or EuRoC layout) with exact ground truth.
    Synth(commands::synth::SynthArgs),
    /// Write a perturbed copy of any sequence (depth, image, time, moving occluders, stereo
    /// misalignment) as a TUM or EuRoC folder any SLAM program reads.
    Perturb(commands::perturb::PerturbArgs),
    /// Download and unpack catalogued sequences (datasets.toml) into the data directory.
    Fetch(commands::fetch::FetchArgs),
    /// Detect ORB features on an image and draw them into a PNG.
    Features(commands::features::FeaturesArgs),
    /// The regression suite: short synthetic sequences x the four configurations against the
    /// golden figures (tests/golden/regression.toml); `--update` rewrites them.
    Regress(commands::regress::RegressArgs),
    /// A sequence's camera as an ORB-SLAM2 / ORB-SLAM3 settings file (YAML), for running
    /// another system on the same files.
    Settings(commands::settings::SettingsArgs),
    /// Every setting of the config TOML (`--config FILE`) with its default, for one sensor: a
    /// file to start from.
    Config(commands::config::ConfigArgs),
    /// Per-frame tracking + mapping cost of each configuration on one sequence, one core, and
    /// the frames per second of a sweep of the paper's four configurations.
    Bench(commands::bench::BenchArgs),
    /// The level of a camera chain at which the baseline's median ATE on a sequence equals a
    /// target (the paper's figure), by bisection.
    Match(commands::match_level::MatchArgs),
    /// Trajectory files aligned to the ground truth as one Rerun recording (`rerun FILE.rrd`).
    View(commands::view::ViewArgs),
    /// Vocabularies of ORB words for place recognition: train, convert (ORBvoc.txt <-> binary), info.
    Vocab(commands::vocab::VocabArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => commands::run::run(a),
        Command::Sweep(a) => commands::sweep::run(*a),
        Command::Table(a) => commands::table::run(a),
        Command::Report(a) => commands::report::run(a),
        Command::Analyze(a) => commands::analyze::run(a),
        Command::Plot(a) => commands::plot::run(a),
        Command::Eval(a) => commands::eval::run(a),
        Command::Synth(a) => commands::synth::run(a),
        Command::Fetch(a) => commands::fetch::run(a),
        Command::Perturb(a) => commands::perturb::run(a),
        Command::Features(a) => commands::features::run(a),
        Command::Regress(a) => commands::regress::run(a),
        Command::Vocab(a) => commands::vocab::run(a),
        Command::Bench(a) => commands::bench::run(a),
        Command::Settings(a) => commands::settings::run(a),
        Command::Config(a) => commands::config::run(a),
        Command::Match(a) => commands::match_level::run(a),
        Command::View(a) => commands::view::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
