//! Reading a file the user names — a parameters file, a URDF, an odometry or scan message:
//! regular files only, and at most [`MAX_INPUT_FILE_BYTES`].
//!
//! `/dev/zero` or `/dev/urandom` given as an input never ends and would be read until memory ran
//! out; a FIFO with no writer would block forever. Every path that reads a user-given file goes
//! through [`read_to_string`], which refuses both up front and says why.

use std::fs::{File, FileType, OpenOptions};
use std::io::{self, Read};
use std::path::Path;

/// The most an input file may hold, bytes (16 MiB). The largest legitimate input is a scan at
/// the accepted 100 000 beams, about 2 MB as JSON; parameter files and URDFs are kilobytes.
pub const MAX_INPUT_FILE_BYTES: u64 = 16 << 20;

/// Reads the regular file at `path` as UTF-8 text; anything else (a device, a FIFO, a socket, a
/// directory) or a file over [`MAX_INPUT_FILE_BYTES`] is an error saying so. Callers name the
/// path, as for any other read error.
pub fn read_to_string(path: &Path) -> io::Result<String> {
    let file = open(path)?;
    let kind = file.metadata()?.file_type();
    if !kind.is_file() {
        return Err(not_regular(kind));
    }
    let mut text = String::new();
    // One byte past the cap tells a file at the cap from a larger one (or one still growing).
    file.take(MAX_INPUT_FILE_BYTES + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > MAX_INPUT_FILE_BYTES {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "it holds more than {} MiB, the most an input file may",
                MAX_INPUT_FILE_BYTES >> 20
            ),
        ));
    }
    Ok(text)
}

/// Opens for reading without blocking on a FIFO that has no writer, so that the file's type can
/// be checked on the open descriptor (no window between the check and the read). Non-blocking
/// mode changes nothing for a regular file.
#[cfg(target_os = "linux")]
fn open(path: &Path) -> io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
}

/// Opens for reading; without Linux's non-blocking open a FIFO is caught before opening.
#[cfg(not(target_os = "linux"))]
fn open(path: &Path) -> io::Result<File> {
    let kind = std::fs::metadata(path)?.file_type();
    if !kind.is_file() {
        return Err(not_regular(kind));
    }
    OpenOptions::new().read(true).open(path)
}

/// The error for a file of type `kind` that is not a regular file.
fn not_regular(kind: FileType) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "it is {}, not a regular file (inputs must be regular files)",
            describe(kind)
        ),
    )
}

/// What kind of file `kind` is, for the error.
fn describe(kind: FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() {
            return "a character device";
        }
        if kind.is_block_device() {
            return "a block device";
        }
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("cstep-input-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn refusal(path: &Path) -> String {
        let err = read_to_string(path).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput, "{err}");
        err.to_string()
    }

    #[test]
    fn regular_files_up_to_the_cap_are_read() {
        let dir = temp_dir("regular");
        let path = dir.join("small.yaml");
        std::fs::write(&path, "a: 1\n").unwrap();
        assert_eq!(read_to_string(&path).unwrap(), "a: 1\n");
        // Sparse: as many zero bytes as the cap allows, without writing them.
        let full = dir.join("full");
        File::create(&full)
            .unwrap()
            .set_len(MAX_INPUT_FILE_BYTES)
            .unwrap();
        assert_eq!(
            read_to_string(&full).unwrap().len() as u64,
            MAX_INPUT_FILE_BYTES
        );
    }

    #[test]
    fn endless_devices_fifos_and_directories_are_refused_saying_what_they_are() {
        // Regression: /dev/zero was read until memory ran out, a FIFO blocked forever.
        assert_eq!(
            refusal(Path::new("/dev/zero")),
            "it is a character device, not a regular file (inputs must be regular files)"
        );
        assert!(refusal(Path::new("/dev/urandom")).contains("a character device"));
        let dir = temp_dir("special");
        assert!(refusal(&dir).starts_with("it is a directory"));
        let fifo = dir.join("fifo");
        let _ = std::fs::remove_file(&fifo);
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.unwrap().success());
        // No writer ever opens it: a blocking read would never return.
        assert!(refusal(&fifo).starts_with("it is a FIFO"));
    }

    #[test]
    fn files_over_the_cap_are_refused() {
        let path = temp_dir("large").join("large.json");
        File::create(&path)
            .unwrap()
            .set_len(MAX_INPUT_FILE_BYTES + 1)
            .unwrap();
        assert_eq!(
            refusal(&path),
            "it holds more than 16 MiB, the most an input file may"
        );
    }
}
