//! The project's versioned JSON files (the network's models and checkpoints, the transport's
//! models): a `format` name and a `version` first, read before anything else, so a file of
//! another kind or version is refused with a clear message instead of a confusing field error.
//! One reader for all of them, here at the bottom so every crate that writes such a file
//! reads it the same way.

use serde::Deserialize;
use serde::de::DeserializeOwned;

/// Only the header.
#[derive(Deserialize)]
struct Header {
    format: Option<String>,
    version: Option<u32>,
}

/// What a versioned file is: its `format` name, the version this build reads, and how its
/// messages name it ("model", "checkpoint").
pub struct Kind {
    /// The `format` name the file must carry.
    pub format: &'static str,
    /// The version this build reads.
    pub version: u32,
    /// How messages name the file ("model", "checkpoint").
    pub noun: &'static str,
    /// What to do about a file of another version.
    pub remedy: &'static str,
}

/// Reads `text` as a file of `kind`; the error is one line saying what is wrong and where.
pub fn read<T: DeserializeOwned>(text: &[u8], kind: &Kind) -> Result<T, String> {
    let noun = kind.noun;
    let header: Header = serde_json::from_slice(text).map_err(|e| {
        format!(
            "not a flatland {noun} (line {}, column {}: {e})",
            e.line(),
            e.column()
        )
    })?;
    if header.format.as_deref() != Some(kind.format) {
        return Err(format!(
            "not a flatland {noun}: `format` must be \"{}\"",
            kind.format
        ));
    }
    match header.version {
        Some(v) if v == kind.version => {}
        Some(v) => {
            return Err(format!(
                "{noun} file version {v}, but this build reads version {}; {}",
                kind.version, kind.remedy
            ));
        }
        None => return Err(format!("{noun} file has no `version`")),
    }
    serde_json::from_slice(text).map_err(|e| {
        format!(
            "malformed {noun} (line {}, column {}): {e}",
            e.line(),
            e.column()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const KIND: Kind = Kind {
        format: "flatland-test",
        version: 2,
        noun: "test file",
        remedy: "write it again",
    };

    #[derive(Deserialize, Debug)]
    struct Body {
        #[allow(dead_code)]
        x: u32,
    }

    #[test]
    fn every_way_a_header_can_be_wrong_is_one_clear_line() {
        let cases = [
            ("{ truncated", "line 1"),
            (r#"{"format":"other","version":2}"#, "`format` must be"),
            (
                r#"{"format":"flatland-test","version":1}"#,
                "version 1, but",
            ),
            (r#"{"format":"flatland-test"}"#, "no `version`"),
            (r#"{"format":"flatland-test","version":2}"#, "malformed"),
        ];
        for (text, expected) in cases {
            let err = read::<Body>(text.as_bytes(), &KIND).unwrap_err();
            assert!(err.contains(expected) && !err.contains('\n'), "{err}");
        }
        let ok: Body = read(br#"{"format":"flatland-test","version":2,"x":1}"#, &KIND).unwrap();
        assert_eq!(ok.x, 1);
    }
}
