//! `noisefree fetch NAME...`: downloads catalogued sequences (datasets.toml) into the data
//! directory with a progress bar, resuming interrupted downloads, unpacking atomically and
//! verifying the result. All the work is in `datasets::fetch`; this module draws the bar.

use anyhow::Context;
use datasets::fetch::{FetchEvent, FetchOptions};
use datasets::{data_root, Catalog, Class, EntryFormat};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `noisefree fetch`.
#[derive(clap::Args, Debug)]
pub struct FetchArgs {
    /// Sequence names from datasets.toml (`fr1_xyz`, `fr3_w_rpy`, `mh04`...), or a group of
    /// Table III: `table3` (all 31), `table3-easy`, `table3-hard`, `tum`, `euroc`.
    #[arg(required_unless_present = "list")]
    pub names: Vec<String>,
    /// Data directory (default: $NOISEFREE_DATA, else ./data).
    #[arg(long)]
    pub data_dir: Option<PathBuf>,
    /// Catalog file to use instead of the built-in datasets.toml.
    #[arg(long)]
    pub catalog: Option<PathBuf>,
    /// Keep the downloaded archive in DATA_DIR/.downloads after unpacking.
    #[arg(long)]
    pub keep_archive: bool,
    /// Connection timeout in seconds.
    #[arg(long, default_value_t = 10)]
    pub timeout: u64,
    /// List the catalogued sequences and whether they are present, then exit.
    #[arg(long)]
    pub list: bool,
}

/// One line per catalogued sequence under a header: its name, Table III class, the twin that
/// imitates it (real sequences) and where it is (present with its path, missing, or
/// synthetic with what it imitates), every column as wide as its longest entry. A closed pipe
/// (`| head`) just ends the listing.
fn write_list(out: &mut impl std::io::Write, catalog: &Catalog, root: &std::path::Path) {
    let rows: Vec<[String; 4]> = catalog
        .entries()
        .iter()
        .map(|e| {
            let state = match e.path(root) {
                Some(p) if p.exists() => format!("present  {}", p.display()),
                Some(_) => "missing".to_string(),
                None => match &e.imitates {
                    Some(row) => format!("synthetic, imitates {row}"),
                    None => "synthetic (noisefree synth)".to_string(),
                },
            };
            let class = e
                .class
                .map(|c| format!("{c:?}").to_lowercase())
                .unwrap_or_else(|| "-".into());
            let twin = if e.is_synthetic() {
                "-".to_string()
            } else {
                catalog
                    .twin_of(&e.name)
                    .map_or_else(|| "-".to_string(), |t| t.name.clone())
            };
            [e.name.clone(), class, twin, state]
        })
        .collect();
    let header = ["name", "class", "twin", "state"].map(String::from);
    let width = |i: usize| {
        std::iter::once(&header)
            .chain(&rows)
            .map(|r| r[i].len())
            .max()
            .unwrap_or(0)
    };
    let (w0, w1, w2) = (width(0), width(1), width(2));
    for r in std::iter::once(&header).chain(&rows) {
        if writeln!(out, "{:<w0$}  {:<w1$}  {:<w2$}  {}", r[0], r[1], r[2], r[3]).is_err() {
            break;
        }
    }
}

/// Runs `noisefree fetch`.
pub fn run(args: FetchArgs) -> anyhow::Result<()> {
    let catalog = match &args.catalog {
        Some(p) => Catalog::load(p)?,
        None => Catalog::embedded(),
    };
    let root = data_root(args.data_dir.as_deref());
    if args.list {
        let mut out = std::io::stdout().lock();
        write_list(&mut out, &catalog, &root);
        return Ok(());
    }
    let mut names: Vec<String> = Vec::new();
    for n in &args.names {
        let group: Vec<String> = match n.as_str() {
            "table3" => catalog
                .entries()
                .iter()
                .filter(|e| !e.is_synthetic())
                .map(|e| e.name.clone())
                .collect(),
            "tum" => catalog
                .by_format(EntryFormat::Tum)
                .map(|e| e.name.clone())
                .collect(),
            "euroc" => catalog
                .by_format(EntryFormat::Euroc)
                .map(|e| e.name.clone())
                .collect(),
            "table3-easy" => catalog
                .by_class(Class::Easy)
                .map(|e| e.name.clone())
                .collect(),
            "table3-hard" => catalog
                .by_class(Class::Hard)
                .map(|e| e.name.clone())
                .collect(),
            _ => vec![catalog.get(n)?.name.clone()],
        };
        for g in group {
            if !names.contains(&g) {
                names.push(g);
            }
        }
    }
    let opts = FetchOptions {
        connect_timeout: Duration::from_secs(args.timeout),
        keep_archive: args.keep_archive,
        ..FetchOptions::default()
    };
    for name in &names {
        let entry = catalog.get(name)?;
        if entry.is_synthetic() {
            eprintln!(
                "{name}: synthetic preset, nothing to download (noisefree synth --preset {})",
                entry.preset.as_deref().unwrap_or(name)
            );
            continue;
        }
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template(
                "{msg:14} [{bar:30}] {bytes}/{total_bytes} {bytes_per_sec} eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_message(name.clone());
        let dir = datasets::fetch::fetch(entry, &root, &opts, &mut |ev| match ev {
            FetchEvent::Start { offset, total, .. } => {
                if let Some(t) = total {
                    bar.set_length(*t);
                }
                bar.set_position(*offset);
            }
            FetchEvent::Progress { done, .. } => bar.set_position(*done),
            FetchEvent::Retrying(n) => {
                bar.println(format!("{name}: transfer broke, resuming ({n})"))
            }
            FetchEvent::Restarted => {
                bar.println(format!("{name}: server cannot resume, restarting"))
            }
            FetchEvent::UsingArchive(p) => bar.println(format!("{name}: using {}", p.display())),
            FetchEvent::Unpacking(_) => bar.set_message(format!("{name} unpack")),
            FetchEvent::AlreadyPresent(_) | FetchEvent::Done(_) => {}
        })
        .with_context(|| format!("fetching {name}"))?;
        bar.finish_and_clear();
        println!("{name}: {}", dir.display());
    }
    Ok(())
}
