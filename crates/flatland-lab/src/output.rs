//! Output paths, checked before a command starts its work, by one rule for every command:
//!
//! - missing folders on the way to an output are created (as `mkdir -p` would);
//! - the output's folder must be writable (a probe file is created there and removed);
//! - an output never overwrites an input of the same command (compared after resolving links);
//! - a file output must not name an existing folder.
//!
//! The writes themselves are atomic ([`flatland_geom::write_atomic`]: a synced temporary file,
//! then a rename) and run under [`crate::interrupt::writing`], so Ctrl-C never cuts one.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

/// Checks a file output: not an input, not a folder, its folder created and writable.
pub fn file(out: &Path, inputs: &[&Path]) -> Result<()> {
    if out.is_dir() {
        bail!(
            "{}: is a folder; give a file name for the output",
            out.display()
        );
    }
    if out.file_name().is_none() {
        bail!("{}: not a file name", out.display());
    }
    refuse_inputs(out, inputs)?;
    folder_ready(&parent_of(out))
}

/// Checks a folder output that will receive `files`: none of them is an input, the folder is
/// created and writable.
pub fn folder(dir: &Path, files: &[&str], inputs: &[&Path]) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        bail!(
            "{}: exists and is not a folder; give a folder for the output",
            dir.display()
        );
    }
    for name in files {
        refuse_inputs(&dir.join(name), inputs)?;
    }
    folder_ready(dir)
}

/// Which of `formats` (lower-case extensions, e.g. `["csv", "png"]`) a file output is, by its
/// extension in any case; any other is refused naming the valid ones, before any work.
pub fn format(out: &Path, formats: &[&'static str]) -> Result<&'static str> {
    let extension = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if let Some(found) = formats.iter().find(|f| extension.as_deref() == Some(**f)) {
        return Ok(found);
    }
    let valid: Vec<String> = formats.iter().map(|f| format!(".{f}")).collect();
    bail!(
        "{}: unknown output format (expected a {} file name)",
        out.display(),
        valid.join(" or ")
    )
}

/// Two outputs of one command must differ.
pub fn distinct(a: &Path, b: &Path, what: &str) -> Result<()> {
    if same_file(a, b) {
        bail!("{}: {what}", a.display());
    }
    Ok(())
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn refuse_inputs(out: &Path, inputs: &[&Path]) -> Result<()> {
    if let Some(input) = inputs.iter().find(|input| same_file(out, input)) {
        bail!(
            "{}: is also an input ({}); an output never overwrites an input, choose another name",
            out.display(),
            input.display()
        );
    }
    Ok(())
}

/// Whether two paths name the same file, after resolving `.`, `..` and links.
fn same_file(a: &Path, b: &Path) -> bool {
    resolve(a) == resolve(b)
}

/// `path` made absolute, `.` and `..` resolved component by component, and every prefix that
/// exists replaced by its canonical form (links resolved), so that a path through folders that
/// do not exist yet (`new/../scene.json`) is still recognised.
fn resolve(path: &Path) -> PathBuf {
    use std::path::Component;
    let absolute = std::env::current_dir().map_or_else(|_| path.to_path_buf(), |d| d.join(path));
    let mut out = PathBuf::new();
    for component in absolute.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => {
                out.push(other);
                if let Ok(real) = out.canonicalize() {
                    out = real;
                }
            }
        }
    }
    out
}

/// Creates `dir` (and its parents) if missing and proves it writable.
fn folder_ready(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the output folder", dir.display()))?;
    let probe = dir.join(format!(".flatland-probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .with_context(|| format!("{}: cannot write in the output folder", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("flatland-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn missing_folders_are_created_and_inputs_refused() {
        let dir = temp("rule");
        let out = dir.join("a/b/model.json");
        file(&out, &[]).unwrap();
        assert!(dir.join("a/b").is_dir());
        assert_eq!(
            std::fs::read_dir(dir.join("a/b")).unwrap().count(),
            0,
            "probe left"
        );

        let scene = dir.join("s.json");
        std::fs::write(&scene, "{}").unwrap();
        // The same file by another spelling is still the same file.
        let other = dir.join("a/../s.json");
        let err = file(&other, &[&scene]).unwrap_err().to_string();
        assert!(err.contains("also an input"), "{err}");
        let err = folder(&dir, &["s.json"], &[&scene])
            .unwrap_err()
            .to_string();
        assert!(err.contains("also an input"), "{err}");
        let err = file(&dir, &[]).unwrap_err().to_string();
        assert!(err.contains("is a folder"), "{err}");
        let err = file(&scene.join("x.png"), &[]).unwrap_err().to_string();
        assert!(err.contains("cannot create the output folder"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
