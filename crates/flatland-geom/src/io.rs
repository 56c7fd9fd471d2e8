//! Scene files: the same schema in RON and JSON, chosen by extension; atomic saves.

use std::path::{Path, PathBuf};

use crate::GeomError;
use crate::scene::{RawScene, Scene};

/// The two file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ron,
    Json,
}

fn format_of(path: &Path) -> Result<Format, GeomError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("ron") => Ok(Format::Ron),
        Some("json") => Ok(Format::Json),
        _ => Err(GeomError::Format {
            path: path.to_path_buf(),
        }),
    }
}

fn parse_json(text: &str, location: &str) -> Result<RawScene, GeomError> {
    serde_json::from_str(text).map_err(|e| {
        let full = e.to_string();
        // serde_json appends " at line L column C"; we put the position in front instead.
        let message = match full.rfind(" at line ") {
            Some(i) => full[..i].to_string(),
            None => full,
        };
        let (line, column) = json_position(text, e.line(), e.column());
        GeomError::Parse {
            location: location.to_string(),
            line,
            column,
            message: one_line(&message),
        }
    })
}

/// serde_json reports an error at a line break (a raw newline in a string, an empty file) as
/// column 0 of the following line; name the end of the line it is on instead, so that every
/// position is 1-based.
fn json_position(text: &str, line: usize, column: usize) -> (usize, usize) {
    if column > 0 || line <= 1 {
        return (line.max(1), column.max(1));
    }
    let previous = text
        .split('\n')
        .nth(line - 2)
        .map_or(0, |l| l.chars().count());
    (line - 1, previous + 1)
}

/// The parser's message on one line: control characters (a newline inside a quoted field name
/// or variant, which the message repeats) are escaped.
fn one_line(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    for c in message.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

fn parse_ron(text: &str, location: &str) -> Result<RawScene, GeomError> {
    ron::from_str(text).map_err(|e| GeomError::Parse {
        location: location.to_string(),
        line: e.span.start.line.max(1),
        column: e.span.start.col.max(1),
        message: one_line(&e.code.to_string()),
    })
}

/// The file's text; a file that is not UTF-8 (a binary file) is a parse error at the first bad
/// byte, not an I/O error without a position.
fn read_text(path: &Path, location: &str) -> Result<String, GeomError> {
    let bytes = std::fs::read(path).map_err(|error| GeomError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let good = std::str::from_utf8(good).unwrap_or_default();
        let line = good.matches('\n').count() + 1;
        let column = good.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        let byte = e.as_bytes()[good.len()];
        GeomError::Parse {
            location: location.to_string(),
            line,
            column,
            message: format!("not a text file: invalid UTF-8 byte 0x{byte:02x}"),
        }
    })
}

impl Scene {
    /// Parses and validates a scene from JSON text.
    pub fn from_json_str(text: &str) -> Result<Scene, GeomError> {
        Scene::try_from(parse_json(text, "")?)
    }

    /// Parses and validates a scene from RON text (`//` comments allowed).
    pub fn from_ron_str(text: &str) -> Result<Scene, GeomError> {
        Scene::try_from(parse_ron(text, "")?)
    }

    /// Loads a `.ron` or `.json` scene file (by extension, case-insensitive). Parse errors read
    /// `file:line:column: message`; validation errors `file: edge N: rule`.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, GeomError> {
        let path = path.as_ref();
        let format = format_of(path)?;
        let location = format!("{}:", path.display());
        let text = read_text(path, &location)?;
        let raw = match format {
            Format::Ron => parse_ron(&text, &location)?,
            Format::Json => parse_json(&text, &location)?,
        };
        Scene::try_from(raw).map_err(|e| GeomError::InvalidFile {
            path: path.to_path_buf(),
            error: Box::new(e),
        })
    }

    /// Saves the scene as `.ron` or `.json` (by extension). Atomic: writes a temporary file in
    /// the same directory and renames it over `path`, so a reader never sees half a file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), GeomError> {
        let path = path.as_ref();
        let text = match format_of(path)? {
            Format::Ron => {
                let config = ron::ser::PrettyConfig::new().depth_limit(3);
                ron::ser::to_string_pretty(&self.to_raw(), config)
                    .map_err(|e| GeomError::Serialize(e.to_string()))?
            }
            Format::Json => serde_json::to_string_pretty(&self.to_raw())
                .map_err(|e| GeomError::Serialize(e.to_string()))?,
        };
        write_atomic(path, format!("{text}\n").as_bytes())
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so a
/// reader sees the old file or the new one, never half of one.
///
/// The data is synced to disk before the rename and the directory after it, so a power cut
/// cannot leave an empty or truncated file under the final name. On any error the temporary
/// file is removed. A temporary file left by a process that was killed while writing (they are
/// named `.NAME.tmpPID`) is removed by the next successful write of the same file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), GeomError> {
    use std::io::Write as _;
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes).map_err(|error| GeomError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    file.commit()
}

/// A file written a piece at a time and put in place whole, as [`write_atomic`] puts its
/// bytes: a buffered temporary file next to `path` that [`AtomicFile::commit`] syncs and
/// renames; dropped without a commit, it is removed and `path` is untouched. For outputs too
/// large to hold in memory (a relighting's B at every position).
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    prefix: std::ffi::OsString,
    file: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Starts the temporary file of `path`.
    pub fn create(path: &Path) -> Result<AtomicFile, GeomError> {
        let io = |error| GeomError::Io {
            path: path.to_path_buf(),
            error,
        };
        let name = path.file_name().ok_or_else(|| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a file name",
            ))
        })?;
        let prefix = tmp_prefix(name);
        let mut tmp_name = prefix.clone();
        tmp_name.push(std::process::id().to_string());
        let tmp: PathBuf = path.with_file_name(tmp_name);
        let file = std::fs::File::create(&tmp).map_err(io)?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            prefix,
            file: Some(std::io::BufWriter::new(file)),
        })
    }

    /// Syncs what was written and puts it in place under its name.
    pub fn commit(mut self) -> Result<(), GeomError> {
        let file = self.file.take().expect("a file until committed");
        let result = file
            .into_inner()
            .map_err(std::io::IntoInnerError::into_error)
            .and_then(|f| f.sync_all())
            .and_then(|()| std::fs::rename(&self.tmp, &self.path));
        match result {
            Ok(()) => {
                sync_folder(&self.path);
                remove_orphans(&self.path, &self.prefix);
                Ok(())
            }
            Err(error) => {
                let _ = std::fs::remove_file(&self.tmp);
                Err(GeomError::Io {
                    path: self.path.clone(),
                    error,
                })
            }
        }
    }
}

impl std::io::Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file
            .as_mut()
            .expect("a file until committed")
            .write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.as_mut().expect("a file until committed").flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// `.NAME.tmp`: the start of every temporary file name of `NAME`.
fn tmp_prefix(name: &std::ffi::OsStr) -> std::ffi::OsString {
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(".tmp");
    prefix
}

/// Makes the rename durable (best effort: some file systems cannot sync a folder).
fn sync_folder(path: &Path) {
    #[cfg(unix)]
    if let Some(folder) = path.parent() {
        let folder = if folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            folder
        };
        if let Ok(f) = std::fs::File::open(folder) {
            let _ = f.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = path;
}

/// Removes `.NAME.tmpPID` files next to `path` whose process no longer runs (Linux, where
/// `/proc` says so; elsewhere nothing is removed).
fn remove_orphans(path: &Path, prefix: &std::ffi::OsStr) {
    if !cfg!(target_os = "linux") {
        return;
    }
    let folder = match path.parent() {
        Some(f) if !f.as_os_str().is_empty() => f,
        _ => Path::new("."),
    };
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    let prefix = prefix.to_string_lossy();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let Some(pid) = name.strip_prefix(prefix.as_ref()) else {
            continue;
        };
        if !pid.is_empty()
            && pid.bytes().all(|b| b.is_ascii_digit())
            && !Path::new("/proc").join(pid).exists()
        {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("flatland-io-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_file_written_in_pieces_appears_whole_on_commit_and_not_at_all_when_dropped() {
        use std::io::Write as _;
        let dir = temp("pieces");
        let path = dir.join("b.csv");
        std::fs::write(&path, "old").unwrap();
        let mut file = AtomicFile::create(&path).unwrap();
        for k in 0..3 {
            writeln!(file, "row {k}").unwrap();
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        file.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "row 0\nrow 1\nrow 2\n"
        );
        let mut dropped = AtomicFile::create(&path).unwrap();
        writeln!(dropped, "half").unwrap();
        drop(dropped);
        assert_eq!(names(&dir), ["b.csv"]);
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "row 0\nrow 1\nrow 2\n"
        );
    }

    #[test]
    fn a_failed_write_leaves_no_temporary_file_and_the_old_file_intact() {
        let dir = temp("failed");
        // The target is a non-empty folder: the rename fails after the data was written.
        std::fs::create_dir_all(dir.join("out.json/inside")).unwrap();
        assert!(write_atomic(&dir.join("out.json"), b"new").is_err());
        assert_eq!(names(&dir), ["out.json"]);
        std::fs::write(dir.join("keep.json"), b"old").unwrap();
        assert!(write_atomic(&dir.join("missing/keep.json"), b"new").is_err());
        assert_eq!(std::fs::read(dir.join("keep.json")).unwrap(), b"old");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_temporary_file_of_a_killed_writer_is_removed_by_the_next_write() {
        let dir = temp("orphan");
        // No process has pid 4 000 000 (above Linux's largest pid); pid 1 always runs; a name
        // that is not a pid is someone else's.
        for name in [".m.json.tmp4000000", ".m.json.tmp1", ".m.json.tmpx"] {
            std::fs::write(dir.join(name), b"half").unwrap();
        }
        write_atomic(&dir.join("m.json"), b"whole").unwrap();
        assert_eq!(std::fs::read(dir.join("m.json")).unwrap(), b"whole");
        let mut expected = vec![".m.json.tmp1", ".m.json.tmpx", "m.json"];
        if !cfg!(target_os = "linux") {
            expected.insert(0, ".m.json.tmp4000000");
        }
        assert_eq!(names(&dir), expected);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn parse_errors_name_file_line_and_column() {
        let dir = std::env::temp_dir().join(format!("flatland-geom-err-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.json");
        std::fs::write(
            &path,
            "{\"edges\": [\n  {\"a\": [0, 0], \"b\": [1, 0], \"reflectence\": 0.5}]}",
        )
        .unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}:2:", path.display())), "{err}");
        assert!(err.contains("reflectence"), "{err}");
        let path = dir.join("bad.ron");
        std::fs::write(
            &path,
            "// comment\n(edges: [\n  (a: (0, 0), b: (1, 0), reflectance: 0.5, role: wall)])",
        )
        .unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}:3:", path.display())), "{err}");
        let path = dir.join("invalid.ron");
        std::fs::write(&path, "(edges: [(a: (0, 0), b: (0, 0), reflectance: 0.5)])").unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.contains("invalid.ron: edge 0: zero length"), "{err}");
        // A two-sided surface: file, edge and how to model a thin wall, on one line.
        let path = dir.join("thin.json");
        std::fs::write(
            &path,
            r#"{"edges": [{"a": [0, 0], "b": [1, 0], "reflectance": 0.5},
                {"a": [1, 0], "b": [0, 1], "reflectance": 0.5, "emission": 1},
                {"a": [0.2, 0.2], "b": [0.4, 0.2], "reflectance": 0.5, "two_sided": true}]}"#,
        )
        .unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "{}: edge 2: a surface cannot be two-sided",
                path.display()
            )),
            "{err}"
        );
        assert!(err.contains("back to back") && !err.contains('\n'), "{err}");
        let err = Scene::load(dir.join("scene.txt")).unwrap_err().to_string();
        assert!(err.contains("unknown scene format"), "{err}");
        let err = Scene::load(dir.join("missing.ron"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing.ron"), "{err}");
        let err = serde_json::from_str::<Scene>(r#"{"edges":[]}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("no surface edge"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
