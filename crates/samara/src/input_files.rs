//! Reading the text files a model names (the model itself, sections tables): regular
//! files only, of bounded size, valid UTF-8 — so a device (`/dev/zero`) or a FIFO is
//! refused at once instead of read until memory runs out or waited on forever.

use std::io::Read;
use std::path::Path;

/// The largest input text file samara reads [bytes].
pub const MAX_INPUT_BYTES: u64 = 128 << 20;

/// Why an input file cannot be read as text.
#[derive(Debug, thiserror::Error)]
pub enum InputFileError {
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("it is not a regular file (a directory, device or pipe)")]
    NotRegular,
    #[error("it is {size} bytes long; input files are limited to {MAX_INPUT_BYTES} bytes")]
    TooLarge { size: u64 },
    /// Not UTF-8: the byte offset of the first invalid byte and the text up to it.
    #[error("it is not UTF-8 text: invalid byte at line {line}, column {column}")]
    NotUtf8 {
        offset: usize,
        line: usize,
        column: usize,
    },
}

/// Reads a regular file of at most [`MAX_INPUT_BYTES`] as UTF-8 text.
pub fn read_text(path: &Path) -> Result<String, InputFileError> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(InputFileError::NotRegular);
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(InputFileError::TooLarge { size: meta.len() });
    }
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may grow between metadata and read: read one byte more than the limit.
    file.take(MAX_INPUT_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(InputFileError::TooLarge {
            size: bytes.len() as u64,
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let good = &e.as_bytes()[..offset];
        // Valid up to `offset`, so this is text.
        let before = std::str::from_utf8(good).unwrap_or_default();
        let line = before.matches('\n').count() + 1;
        let column = before[before.rfind('\n').map_or(0, |i| i + 1)..]
            .chars()
            .count()
            + 1;
        InputFileError::NotUtf8 {
            offset,
            line,
            column,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_bad_bytes_are_refused() {
        assert!(matches!(
            read_text(Path::new("/dev/zero")),
            Err(InputFileError::NotRegular)
        ));
        let dir = tempfile::tempdir().unwrap();
        assert!(matches!(
            read_text(dir.path()),
            Err(InputFileError::NotRegular)
        ));
        let p = dir.path().join("m.toml");
        std::fs::write(&p, b"[model]\nname = \"a\xffb\"\n").unwrap();
        match read_text(&p) {
            Err(InputFileError::NotUtf8 {
                offset,
                line,
                column,
            }) => {
                assert_eq!((offset, line, column), (17, 2, 10));
            }
            other => panic!("{other:?}"),
        }
        std::fs::write(&p, "[model]\nname = \"é\"\n").unwrap();
        assert!(read_text(&p).is_ok());
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("fifo");
        let ok = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .is_ok_and(|s| s.success());
        assert!(ok, "mkfifo (coreutils) makes the pipe");
        assert!(matches!(read_text(&p), Err(InputFileError::NotRegular)));
    }
}
