//! How every table is written: one [`Rendered`] per table (Markdown with its heading and notes,
//! and a CSV of the same rows), and the headings systems go by.

use crate::columns::ConfigKind;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// A rendered table: Markdown and CSV of the same content.
#[derive(Clone, Debug, Default)]
pub struct Rendered {
    /// Markdown (with a heading and notes).
    pub markdown: String,
    /// CSV.
    pub csv: String,
}

/// Renders a table (heading, header, rows, notes) as Markdown, and its header and rows as CSV.
pub fn render(title: &str, notes: &str, header: &[String], rows: &[Vec<String>]) -> Rendered {
    let mut md = format!("## {title}\n\n");
    let _ = writeln!(md, "| {} |", header.join(" | "));
    let _ = writeln!(
        md,
        "|{}|",
        header.iter().map(|_| "---").collect::<Vec<_>>().join("|")
    );
    for r in rows {
        let _ = writeln!(md, "| {} |", r.join(" | "));
    }
    if !notes.is_empty() {
        let _ = write!(md, "\n{notes}\n");
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(header);
    for r in rows {
        let _ = w.write_record(r);
    }
    let csv = String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default();
    Rendered { markdown: md, csv }
}

/// The paper's column heading of one of our configurations.
pub fn column_name(k: ConfigKind) -> &'static str {
    match k {
        ConfigKind::Orb => "ORB-SLAM2",
        ConfigKind::Mcor => "w/ MC-OR",
        ConfigKind::Avc => "w/ AVC",
        ConfigKind::McorAvc => "w/ MC-OR+AVC",
        ConfigKind::McorFrames => "w/ MC-OR (every frame)",
        ConfigKind::McorFramesAvc => "w/ MC-OR (every frame)+AVC",
        ConfigKind::McorKeyframes => "w/ MC-OR (keyframes)",
        ConfigKind::McorKeyframesAvc => "w/ MC-OR (keyframes)+AVC",
        ConfigKind::Rc => "noisefree: rigid consensus",
    }
}

/// The heading of a system: ours by their column names (the baseline marked as ours), an
/// external one by its definition's label.
pub fn system_label(config: &str, labels: &BTreeMap<String, String>) -> String {
    match ConfigKind::parse(config) {
        Ok(ConfigKind::Orb) => "ORB-SLAM2 (ours)".into(),
        Ok(k) => format!("{} (ours)", column_name(k)),
        Err(_) => match crate::readings::ReadingColumn::parse(config) {
            Ok(Some(r)) => format!("{} [{}] (ours)", column_name(r.kind), r.label()),
            _ => labels
                .get(config)
                .cloned()
                .unwrap_or_else(|| config.to_string()),
        },
    }
}

/// `n` with its noun in the number it takes ("1 table", "3 tables"): a report read on a
/// user's one-folder sweep must not say "1 tables".
pub fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

#[cfg(test)]
mod counted_tests {
    #[test]
    fn one_takes_the_singular_and_every_other_count_the_plural() {
        assert_eq!(super::counted(1, "table", "tables"), "1 table");
        assert_eq!(super::counted(0, "table", "tables"), "0 tables");
        assert_eq!(super::counted(28, "table", "tables"), "28 tables");
    }
}
