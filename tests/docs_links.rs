//! The guide and the reference hold together: every relative link of README.md, docs/ and
//! results/README.md resolves (to a file, and a `#anchor` to a heading of it, as GitHub slugs
//! headings), and README.md stays a guide (under 400 lines, no line over 400 characters outside
//! code blocks).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The lines of `text` outside fenced code blocks, with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut fence: Option<&str> = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        let marker = ["```", "~~~"].into_iter().find(|m| t.starts_with(m));
        match (fence, marker) {
            (None, Some(m)) => fence = Some(m),
            (Some(f), Some(m)) if f == m => fence = None,
            (None, None) => out.push((i + 1, line)),
            _ => {}
        }
    }
    out
}

/// GitHub's anchor of a heading: lower case, letters, digits, spaces, hyphens and underscores
/// kept (a link's text kept, its target dropped), spaces as hyphens.
fn slug(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading;
    // [text](target) -> text
    while let Some(open) = rest.find('[') {
        text.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        match (after.find("]("), after.find(')')) {
            (Some(close), Some(end)) if close < end => {
                text.push_str(&after[..close]);
                rest = &after[end + 1..];
            }
            _ => {
                text.push('[');
                rest = after;
            }
        }
    }
    text.push_str(rest);
    text.trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings (repeats numbered as GitHub numbers them).
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    for (_, line) in prose_lines(text) {
        let hashes = line.chars().take_while(|c| *c == '#').count();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        let s = slug(line[hashes..].trim().trim_end_matches('#').trim());
        let n = seen.entry(s.clone()).or_insert(0);
        out.insert(if *n == 0 {
            s.clone()
        } else {
            format!("{s}-{n}")
        });
        *n += 1;
    }
    out
}

/// The targets of the Markdown links of a line (`[text](target)`, images too), inline code
/// left out.
fn link_targets(line: &str) -> Vec<String> {
    let mut clean = String::new();
    let mut in_code = false;
    for c in line.chars() {
        if c == '`' {
            in_code = !in_code;
        } else if !in_code {
            clean.push(c);
        }
    }
    let mut out = Vec::new();
    let mut rest = clean.as_str();
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let end = after.find(')').unwrap_or(after.len());
        let target = after[..end].split_whitespace().next().unwrap_or("");
        out.push(target.trim_matches(['<', '>']).to_string());
        rest = &after[end.min(after.len())..];
    }
    out
}

/// Every broken relative link of `file` (relative to the repository), as `file:line: target`.
fn broken_links(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(root().join(file)).unwrap();
    let dir = root().join(file).parent().unwrap().to_path_buf();
    let mut broken = Vec::new();
    for (n, line) in prose_lines(&text) {
        for target in link_targets(line) {
            if target.is_empty()
                || target.contains("://")
                || target.starts_with("mailto:")
                || target.starts_with('{')
            {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() {
                root().join(file)
            } else {
                dir.join(path)
            };
            let ok = resolved.exists()
                && match anchor {
                    Some(a) if resolved.extension().is_some_and(|e| e == "md") => {
                        let t = std::fs::read_to_string(&resolved).unwrap_or_default();
                        anchors(&t).contains(a)
                    }
                    _ => true,
                };
            if !ok {
                broken.push(format!("{}:{n}: {target}", file.display()));
            }
        }
    }
    broken
}

#[test]
fn every_relative_link_of_the_guide_the_reference_and_the_results_resolves() {
    let mut files = vec![
        PathBuf::from("README.md"),
        PathBuf::from("results/README.md"),
    ];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .map(|p| p.strip_prefix(root()).unwrap().to_path_buf())
        .collect();
    docs.sort();
    assert!(docs.len() >= 5, "docs/ holds the reference: {docs:?}");
    files.extend(docs);
    let broken: Vec<String> = files.iter().flat_map(|f| broken_links(f)).collect();
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_readme_is_a_guide_not_a_manual() {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = text.lines().count();
    assert!(lines < 400, "README.md has {lines} lines");
    let long: Vec<String> = prose_lines(&text)
        .into_iter()
        .filter(|(_, l)| l.chars().count() > 400)
        .map(|(n, l)| format!("line {n}: {} characters", l.chars().count()))
        .collect();
    assert!(long.is_empty(), "{}", long.join("\n"));
}

#[test]
fn the_checker_knows_a_broken_link_and_a_heading_from_a_code_line() {
    assert_eq!(
        slug("readings/ — every reading (issue 72)"),
        "readings--every-reading-issue-72"
    );
    assert_eq!(slug("[Table III](x.md) on twins"), "table-iii-on-twins");
    let a = anchors("# A\n```\n# not a heading\n```\n## A\n");
    assert_eq!(a, ["a".to_string(), "a-1".to_string()].into());
    assert_eq!(
        link_targets("see [a](b.md#c) and `[x](y)` and ![p](f.png)"),
        ["b.md#c", "f.png"]
    );
}
