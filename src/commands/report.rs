//! `noisefree report`: the findings of committed tables — each claim of the paper with our
//! verdict, the effect and its interval, and a link to the table behind it — printed, written
//! into a Markdown file's findings block, or checked against it.

use crate::report::findings::{findings, splice};
use anyhow::{bail, Context, Result};
use atomic_file::write as write_atomic;
use datasets::Catalog;
use std::path::{Path, PathBuf};

/// Arguments of `noisefree report`.
#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// Folders whose tables to read (`versus-baseline.csv`, `table4.csv`, `table2_*.csv`)
    /// [default: every folder under results/ that has one].
    pub dirs: Vec<PathBuf>,
    /// Write the findings into this Markdown file, between its `<!-- findings: begin ... -->`
    /// and `<!-- findings: end -->` lines, and their counts between its `<!-- glance: begin
    /// ... -->` and `<!-- glance: end -->` lines (whichever it has; links relative to its
    /// folder).
    #[arg(long, value_name = "FILE.md", conflicts_with = "check")]
    pub write: Option<PathBuf>,
    /// Exit with an error when this file's findings or glance block differs from the findings the
    /// tables give now (what CI runs on results/README.md).
    #[arg(long, value_name = "FILE.md")]
    pub check: Option<PathBuf>,
}

/// Every folder under `root` (itself included) with a table the findings read, sorted.
fn table_folders(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        let has = ["versus-baseline.csv", "table4.csv"]
            .iter()
            .any(|f| d.join(f).is_file())
            || std::fs::read_dir(&d).is_ok_and(|it| {
                it.filter_map(|e| e.ok())
                    .any(|e| e.file_name().to_string_lossy().starts_with("table2_"))
            });
        if has {
            out.push(d.clone());
        }
        if let Ok(it) = std::fs::read_dir(&d) {
            for e in it.filter_map(|e| e.ok()) {
                let p = e.path();
                let name = e.file_name().to_string_lossy().into_owned();
                // Run outputs and caches hold no tables.
                if p.is_dir()
                    && !["trajectories", "cache", "external", "figures"].contains(&name.as_str())
                {
                    stack.push(p);
                }
            }
        }
    }
    out.sort();
    out
}

/// Runs `noisefree report`.
pub fn run(args: ReportArgs) -> Result<()> {
    let target = args.write.as_ref().or(args.check.as_ref());
    let base = target
        .and_then(|f| f.parent().map(Path::to_path_buf))
        .unwrap_or_else(|| PathBuf::from("."));
    let dirs = if args.dirs.is_empty() {
        table_folders(Path::new("results"))
    } else {
        args.dirs.clone()
    };
    if dirs.is_empty() {
        bail!("no folder with tables found under results/; pass the folders to read");
    }
    for d in &dirs {
        if !d.is_dir() {
            bail!("{}: not a folder", d.display());
        }
    }
    let md = findings(&dirs, &base, &Catalog::embedded())?;
    match (&args.write, &args.check) {
        (Some(file), _) => {
            // A new file gets a findings block to fill.
            let text = if file.exists() {
                std::fs::read_to_string(file)
                    .with_context(|| format!("reading {}", file.display()))?
            } else {
                format!(
                    "{}\n{}\n",
                    crate::report::findings::BEGIN,
                    crate::report::findings::END
                )
            };
            let out = splice(&text, &md).with_context(|| file.display().to_string())?;
            write_atomic(file, out.as_bytes())?;
            eprintln!(
                "wrote the findings of {} into {}",
                crate::report::markdown::counted(dirs.len(), "folder", "folders"),
                file.display()
            );
        }
        (None, Some(file)) => {
            let text = std::fs::read_to_string(file)
                .with_context(|| format!("reading {}", file.display()))?;
            let want = splice(&text, &md).with_context(|| file.display().to_string())?;
            if want != text {
                bail!(
                    "{}: its findings differ from what the tables give now; run `noisefree report --write {}`",
                    file.display(),
                    file.display()
                );
            }
            eprintln!(
                "{}: findings agree with the tables of {}",
                file.display(),
                crate::report::markdown::counted(dirs.len(), "folder", "folders")
            );
        }
        (None, None) => print!("{}", md.full),
    }
    Ok(())
}
