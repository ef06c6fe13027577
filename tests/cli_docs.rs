//! The README and docs/*.md as a reader of a fresh clone meets them: every relative link
//! resolves to a file or folder inside the repository (no link to a sibling checkout or to a
//! file the clone does not have), and the README names the commands it tells the reader to run.

use std::path::{Path, PathBuf};

/// The targets of the Markdown links `[text](target)` in `text`, with their line numbers.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let Some(end) = rest.find(')') else { break };
            out.push((n + 1, rest[..end].trim().to_string()));
            rest = &rest[end..];
        }
    }
    out
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .canonicalize()
        .unwrap()
}

/// The Markdown files a reader is sent to: README.md and docs/*.md.
fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md")];
    for e in std::fs::read_dir(root().join("docs")).unwrap().flatten() {
        if e.path().extension().is_some_and(|x| x == "md") {
            docs.push(e.path());
        }
    }
    docs
}

#[test]
fn every_relative_link_resolves_inside_the_repository() {
    let root = root();
    let mut bad = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for (line, target) in links(&text) {
            let target = target.split_whitespace().next().unwrap_or("");
            if target.is_empty()
                || target.starts_with('#')
                || target.contains("://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            let path = target.split('#').next().unwrap_or(target);
            let resolved = doc.parent().unwrap().join(path);
            checked += 1;
            match resolved.canonicalize() {
                Ok(p) if p.starts_with(&root) => {}
                Ok(p) => bad.push(format!(
                    "{}:{line}: {target} leaves the repository ({})",
                    doc.display(),
                    p.display()
                )),
                Err(_) => bad.push(format!("{}:{line}: {target} does not exist", doc.display())),
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    assert!(
        checked > 10,
        "only {checked} links found: the parser misses them"
    );
}

/// The link parser itself: finds each target once, on its line.
#[test]
fn links_are_found() {
    let text = "see [a](docs/A.md) and [b](../x.md#part)\n[c](https://e.org) no link (here)";
    assert_eq!(
        links(text),
        [
            (1, "docs/A.md".to_string()),
            (1, "../x.md#part".into()),
            (2, "https://e.org".into())
        ]
    );
}

/// The README's commands are the program's: `nonlin3d run`, `nonlin3d solve`, and the output
/// files it promises are the ones the program writes.
#[test]
fn the_readme_names_the_real_commands_and_files() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    for needle in [
        "cargo run --release",
        " solve ",
        "results.json",
        "status.sta",
        "convergence.cvg",
        "manifest.json",
        "model.pvd",
    ] {
        assert!(readme.contains(needle), "README lacks {needle:?}");
    }
}
