//! `noisefree table`: turns the run records of sweeps (`runs.csv` and shard files, merged) into
//! the paper's tables, as Markdown and tidy CSV beside the records, the figures, and an index
//! (`README.md`) that links every table and shows every figure, so the folder reads as a report
//! on GitHub or in any Markdown viewer.

use crate::report::folder::tables_for;
use crate::sweep::store::is_sweep_dir;
use anyhow::{bail, Result};
use datasets::Catalog;
use std::path::PathBuf;

/// Arguments of `noisefree table`.
#[derive(clap::Args, Debug)]
pub struct TableArgs {
    /// Sweep folders (holding runs.csv or runs.shard-K-of-N.csv) [default: every such folder
    /// under results/].
    pub dirs: Vec<PathBuf>,
    /// Print the paper's published numbers beside ours in Table III.
    #[arg(long)]
    pub paper: bool,
    /// Also print the Markdown to standard output.
    #[arg(long)]
    pub print: bool,
}

/// Runs `noisefree table`.
pub fn run(args: TableArgs) -> Result<()> {
    let catalog = Catalog::embedded();
    let dirs: Vec<PathBuf> = if args.dirs.is_empty() {
        let mut v: Vec<PathBuf> = std::fs::read_dir("results")
            .map(|it| {
                it.filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| is_sweep_dir(p))
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    } else {
        args.dirs.clone()
    };
    if dirs.is_empty() {
        bail!("no sweep folder found under results/; pass the folder of a `noisefree sweep --out DIR`");
    }
    for d in &dirs {
        let md = tables_for(d, &catalog, args.paper)?;
        eprintln!(
            "wrote {0}/tables.md, {0}/table*.csv and {0}/figures/",
            d.display()
        );
        if args.print {
            println!("{md}");
        }
    }
    Ok(())
}
