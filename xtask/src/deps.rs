//! `cargo xtask unused-deps` (and a test CI runs): every dependency a workspace member declares is used in its
//! sources (a `name::` path, `use name`, or `extern crate`), dev-dependencies in its sources,
//! tests, benches or examples. A rough check in the manner of cargo-machete, with no tool to
//! install: it reads the manifests as text and searches the Rust files for the crate's name.

use std::path::{Path, PathBuf};

/// The names declared under `[section]` of a manifest (`name = …` or `name.workspace = …`).
fn declared(manifest: &str, section: &str) -> Vec<String> {
    let mut inside = false;
    let mut names = Vec::new();
    for line in manifest.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            inside = t == format!("[{section}]");
            continue;
        }
        if !inside || t.is_empty() || t.starts_with('#') {
            continue;
        }
        let name: String = t
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
            .collect();
        if !name.is_empty() {
            names.push(name);
        }
    }
    names
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Whether `text` uses the crate `ident` (its name with `-` as `_`) as a path or import.
fn uses(text: &str, ident: &str) -> bool {
    text.match_indices(ident).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = &text[i + ident.len()..];
        let word_start = !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
        word_start && (after.starts_with("::") || text[..i].trim_end().ends_with("use"))
    }) || text.contains(&format!("extern crate {ident}"))
        || text.contains(&format!("value_parser!({ident}"))
}

/// The unused dependencies of the member at `dir`, as `section: name`.
fn unused_in(dir: &Path) -> Result<Vec<String>, String> {
    let manifest = std::fs::read_to_string(dir.join("Cargo.toml"))
        .map_err(|e| format!("{}: {e}", dir.join("Cargo.toml").display()))?;
    let mut found = Vec::new();
    for (section, folders) in [
        ("dependencies", &["src"][..]),
        (
            "dev-dependencies",
            &["src", "tests", "benches", "examples"][..],
        ),
    ] {
        let mut files = Vec::new();
        for f in folders {
            rust_files(&dir.join(f), &mut files);
        }
        let texts: Vec<String> = files
            .iter()
            .filter_map(|f| std::fs::read_to_string(f).ok())
            .collect();
        for name in declared(&manifest, section) {
            let ident = name.replace('-', "_");
            if !texts.iter().any(|t| uses(t, &ident)) {
                found.push(format!("{section}: {name}"));
            }
        }
    }
    Ok(found)
}

/// Check every member; print what is unused and fail if anything is.
pub fn run() -> Result<(), String> {
    let root = hyst_testkit::workspace_root();
    let mut members = vec![root.clone(), root.join("xtask"), root.join("xtask/studies")];
    let mut crates: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .map_err(|e| format!("crates/: {e}"))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    crates.sort();
    members.extend(crates);
    let mut bad = 0;
    for m in &members {
        for u in unused_in(m)? {
            println!(
                "{}: unused {u}",
                m.strip_prefix(&root).unwrap_or(m).display()
            );
            bad += 1;
        }
    }
    if bad > 0 {
        return Err(format!("{bad} unused dependencies"));
    }
    println!("unused-deps: {} members, none unused", members.len());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declared_names_and_uses() {
        let m = "[package]\nname = \"x\"\n[dependencies]\nserde = { workspace = true }\nhyst-model.workspace = true\n# c\n[dev-dependencies]\napprox.workspace = true\n";
        assert_eq!(declared(m, "dependencies"), ["serde", "hyst-model"]);
        assert_eq!(declared(m, "dev-dependencies"), ["approx"]);
        assert!(uses("use hyst_model::Oscillator;", "hyst_model"));
        assert!(uses("let v = serde_json::to_value(x);", "serde_json"));
        assert!(!uses("let v = serde_json::to_value(x);", "serde"));
        assert!(!uses("// my_hyst_model::x", "hyst_model"));
    }

    /// CI's check: `cargo test --workspace` runs it, so a dependency left unused fails CI.
    #[test]
    fn the_workspace_has_no_unused_dependencies() {
        run().unwrap();
    }
}
