//! `cargo xtask sizes` (and a test CI runs): the workspace's rooms stay the size one can read.
//! No source file holds more than [`MAX_FILE_LINES`] lines of code outside its tests, no
//! function is longer than [`MAX_FN_LINES`] lines, the binary's `main.rs` stays under
//! [`MAX_MAIN_LINES`] lines, and the command line builds no JSON by hand (`json!`): its
//! reports are library types written by serde.
//!
//! Lines of code are the lines left, not blank, once comments and the text of string and
//! character literals are taken out; test code is a `#[cfg(test)] mod … { … }` block, a file
//! named `tests.rs` or `*_tests.rs`, or a file under a `tests` or `examples` folder.

use std::path::{Path, PathBuf};

/// Most lines of code a source file may hold outside its tests.
pub const MAX_FILE_LINES: usize = 800;
/// Most lines a function may span (signature to closing brace).
pub const MAX_FN_LINES: usize = 120;
/// Most lines `src/main.rs` may have.
pub const MAX_MAIN_LINES: usize = 60;

/// `src` with comments removed and the text of string and character literals blanked (their
/// quotes kept), each newline kept, so that line numbers and braces are those of the code.
fn strip(src: &str) -> String {
    let b: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(b[i]));
                    i += 1;
                }
            }
        } else if c == 'r'
            && matches!(next, Some('"') | Some('#'))
            && !(i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_'))
        {
            // A raw string r#"…"#: its hashes, then its text up to the same closing.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            out.push('"');
            while j < b.len() {
                if b[j] == '"' && (0..hashes).all(|h| b.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                out.push(blank(b[j]));
                j += 1;
            }
            out.push('"');
            i = j;
        } else if c == '"' {
            out.push('"');
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                if i < b.len() {
                    out.push(blank(b[i]));
                    i += 1;
                }
            }
            out.push('"');
            i += 1;
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}'), not a lifetime ('a).
            let close = if next == Some('\\') {
                (i + 2..b.len().min(i + 12)).find(|&k| b[k] == '\'')
            } else {
                (b.get(i + 2) == Some(&'\'')).then_some(i + 2)
            };
            match close {
                Some(k) => {
                    out.push_str("' '");
                    i = k + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// The index of the brace closing the one at `open` (by counting), or the text's end.
fn closing(s: &[u8], open: usize) -> usize {
    let mut depth = 0i64;
    for (k, &c) in s.iter().enumerate().skip(open) {
        match c {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
            _ => {}
        }
    }
    s.len()
}

/// Line (0-based) of the byte `at`.
fn line_of(s: &[u8], at: usize) -> usize {
    s[..at.min(s.len())].iter().filter(|&&c| c == b'\n').count()
}

/// What one file holds: its lines of code outside tests, and each function outside tests
/// as (name, first line 1-based, lines spanned).
struct FileSizes {
    code_lines: usize,
    functions: Vec<(String, usize, usize)>,
}

fn measure(src: &str) -> FileSizes {
    let s = strip(src);
    let in_test = test_lines(&s);
    let code_lines = s
        .lines()
        .enumerate()
        .filter(|(n, l)| !l.trim().is_empty() && !in_test[*n])
        .count();
    let functions = functions(&s)
        .into_iter()
        .filter(|(_, first, _)| !in_test[first - 1])
        .collect();
    FileSizes {
        code_lines,
        functions,
    }
}

/// Whether each line of the stripped text `s` lies in a `#[cfg(test)] mod … { … }` block.
fn test_lines(s: &str) -> Vec<bool> {
    let bytes = s.as_bytes();
    let mut in_test = vec![false; s.lines().count() + 1];
    let mut from = 0;
    while let Some(k) = s[from..].find("#[cfg(test)]") {
        let at = from + k;
        let rest = &s[at + 12..];
        let trimmed = rest.trim_start();
        let is_mod = trimmed.starts_with("mod ")
            || trimmed.starts_with("pub mod ")
            || trimmed.starts_with("pub(super) mod ")
            || trimmed.starts_with("pub(crate) mod ");
        if let Some(brace) = rest.find(['{', ';'])
            && is_mod
            && rest.as_bytes()[brace] == b'{'
        {
            let end = closing(bytes, at + 12 + brace);
            for flag in in_test
                .iter_mut()
                .take(line_of(bytes, end) + 1)
                .skip(line_of(bytes, at))
            {
                *flag = true;
            }
        }
        from = at + 12;
    }
    in_test
}

/// Every function with a body in the stripped text `s`, as (name, first line 1-based,
/// lines spanned).
fn functions(s: &str) -> Vec<(String, usize, usize)> {
    let bytes = s.as_bytes();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = s[from..].find("fn ") {
        let at = from + k;
        from = at + 3;
        let word_start =
            at == 0 || !(bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_');
        let name: String = s[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        // The body's brace, unless a `;` ends a declaration first.
        let Some(end_sig) = s[at..].find(['{', ';']) else {
            continue;
        };
        if !word_start || name.is_empty() || bytes[at + end_sig] == b';' {
            continue;
        }
        let close = closing(bytes, at + end_sig);
        let first = line_of(bytes, at);
        out.push((name, first + 1, line_of(bytes, close) - first + 1));
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() {
            if !matches!(name, "target" | ".git") && !name.starts_with('.') {
                rust_files(&p, out);
            }
        } else if name.ends_with(".rs") {
            out.push(p);
        }
    }
}

/// Whether `path` (relative to the workspace) is test or example code as a whole.
fn is_test_file(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    name == "tests.rs"
        || name.ends_with("_tests.rs")
        || path
            .components()
            .any(|c| matches!(c.as_os_str().to_str(), Some("tests" | "examples")))
}

/// Every breach of the limits in the workspace at `root`, one line each.
pub fn breaches(root: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(root, &mut files);
    files.sort();
    let mut out = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(root).unwrap_or(f);
        let Ok(src) = std::fs::read_to_string(f) else {
            out.push(format!("{}: unreadable", rel.display()));
            continue;
        };
        if rel == Path::new("src/main.rs") && src.lines().count() >= MAX_MAIN_LINES {
            out.push(format!(
                "src/main.rs: {} lines (under {MAX_MAIN_LINES} wanted: it only parses and dispatches)",
                src.lines().count()
            ));
        }
        if rel.starts_with("src") && src.contains("json!") {
            out.push(format!(
                "{}: builds JSON by hand (json!); write a library type with serde",
                rel.display()
            ));
        }
        if is_test_file(rel) {
            continue;
        }
        let m = measure(&src);
        if m.code_lines > MAX_FILE_LINES {
            out.push(format!(
                "{}: {} lines of code outside its tests (at most {MAX_FILE_LINES})",
                rel.display(),
                m.code_lines
            ));
        }
        for (name, line, len) in m.functions {
            if len > MAX_FN_LINES {
                out.push(format!(
                    "{}:{line}: fn {name} spans {len} lines (at most {MAX_FN_LINES})",
                    rel.display()
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Comments and literals do not count, nor do braces inside them; a lifetime is not a
    /// character literal.
    #[test]
    fn code_lines_and_functions_are_measured() {
        let src = "// a comment {\n\
                   /* a block\n   comment */\n\
                   fn short<'a>(x: &'a str) -> char {\n    let _ = \"}{\";\n    '}'\n}\n\
                   \n\
                   #[cfg(test)]\nmod tests {\n    fn long() {\n    }\n}\n";
        let m = measure(src);
        // fn short's four lines: the comment lines and the test module do not count.
        assert_eq!(m.code_lines, 4, "{}", strip(src));
        assert_eq!(m.functions, vec![("short".to_string(), 4, 4)]);
        let raw = "fn raw() {\n    let _ = r#\"{ \"quoted\" }\"#;\n}\n";
        assert_eq!(measure(raw).functions, vec![("raw".to_string(), 1, 3)]);
        // A function past the limit is measured as long as it is.
        let long = format!(
            "fn long() {{\n{}}}\n",
            "    let _ = 1;\n".repeat(MAX_FN_LINES)
        );
        assert_eq!(
            measure(&long).functions,
            vec![("long".to_string(), 1, MAX_FN_LINES + 2)]
        );
    }

    /// The workspace keeps to the limits (CI runs this).
    #[test]
    fn the_workspace_keeps_its_sizes() {
        let root = hyst_testkit::workspace_root();
        let found = breaches(&root);
        assert!(found.is_empty(), "{}", found.join("\n"));
    }
}
