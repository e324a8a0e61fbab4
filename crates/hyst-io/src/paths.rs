//! Outputs that would overwrite inputs: refused before anything is read or written.

use std::path::{Path, PathBuf};

use super::IoError;

/// Refuse `outputs` (each with the flag that named it) when one of them is one of the
/// `inputs`' files (the same file by any path: relative, absolute, through a symbolic link,
/// or a hard link), or two of them are one file. Call it before reading anything: a command
/// asked to write its report over its record must not destroy the record.
pub fn check_outputs(inputs: &[(&str, &Path)], outputs: &[(&str, &Path)]) -> Result<(), IoError> {
    let ins: Vec<(&str, Identity)> = inputs
        .iter()
        .map(|(flag, p)| (*flag, Identity::of(p)))
        .collect();
    let mut seen: Vec<(&str, Identity)> = Vec::new();
    for (flag, path) in outputs {
        let id = Identity::of(path);
        if let Some((input_flag, _)) = ins.iter().find(|(_, i)| i.same(&id)) {
            return Err(IoError::OutputIsInput {
                output_flag: flag.to_string(),
                input_flag: input_flag.to_string(),
                path: path.to_path_buf(),
            });
        }
        if let Some((first, _)) = seen.iter().find(|(_, i)| i.same(&id)) {
            return Err(IoError::OutputsCollide {
                first_flag: first.to_string(),
                second_flag: flag.to_string(),
                path: path.to_path_buf(),
            });
        }
        seen.push((flag, id));
    }
    Ok(())
}

/// What makes two paths one file: the canonical path (the file's, or its folder's with its
/// name when it does not exist yet), and on Unix the device and inode of an existing file
/// (hard links).
struct Identity {
    path: PathBuf,
    inode: Option<(u64, u64)>,
}

impl Identity {
    fn of(p: &Path) -> Identity {
        let path = std::fs::canonicalize(p).unwrap_or_else(|_| {
            let parent = p.parent().filter(|d| !d.as_os_str().is_empty());
            let dir = parent.map_or_else(
                || std::env::current_dir().ok(),
                |d| std::fs::canonicalize(d).ok(),
            );
            match (dir, p.file_name()) {
                (Some(d), Some(name)) => d.join(name),
                _ => p.to_path_buf(),
            }
        });
        Identity {
            path,
            inode: inode(p),
        }
    }

    fn same(&self, other: &Identity) -> bool {
        self.path == other.path || (self.inode.is_some() && self.inode == other.inode)
    }
}

#[cfg(unix)]
fn inode(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode(_: &Path) -> Option<(u64, u64)> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same file by another spelling, a symbolic and a hard link is refused, naming both
    /// flags; two outputs on one new file likewise; distinct files pass.
    #[test]
    fn an_output_on_an_input_is_refused_by_any_path() {
        let dir = std::env::temp_dir().join(format!("hyst-paths-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rec = dir.join("rec.csv");
        std::fs::write(&rec, "y\n1\n2\n").unwrap();
        let sym = dir.join("sym.csv");
        let hard = dir.join("hard.csv");
        let _ = std::fs::remove_file(&sym);
        let _ = std::fs::remove_file(&hard);
        #[cfg(unix)]
        std::os::unix::fs::symlink(&rec, &sym).unwrap();
        std::fs::hard_link(&rec, &hard).unwrap();
        let odd = dir.join(".").join("rec.csv");
        for (i, p) in [&rec, &odd, &sym, &hard].iter().enumerate() {
            if i == 2 && !cfg!(unix) {
                continue;
            }
            let e = check_outputs(&[("--input", &rec)], &[("--json", p)]).unwrap_err();
            let text = e.to_string();
            assert!(
                text.contains("--json") && text.contains("--input"),
                "{text}"
            );
            assert!(text.contains("overwrite the input"), "{text}");
        }
        let new = dir.join("out.json");
        let e =
            check_outputs(&[("--input", &rec)], &[("--json", &new), ("--svg", &new)]).unwrap_err();
        assert!(e.to_string().contains("--json and --svg both name"), "{e}");
        check_outputs(
            &[("--input", &rec)],
            &[("--json", &new), ("--svg", &dir.join("d.svg"))],
        )
        .unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
