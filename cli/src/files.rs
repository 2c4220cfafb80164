//! The user's files read and written whole, every error naming the file
//! ([`Error::File`] with the system's words).

use std::fs;
use std::io::Write;
use std::path::Path;

use crate::error::Error;

/// Reads a whole text file.
pub fn read_text(path: &Path) -> Result<String, Error> {
    fs::read_to_string(path).map_err(|error| Error::File {
        path: path.display().to_string(),
        error,
    })
}

/// Writes a file; refuses to replace one unless `force`.
pub fn write_new(path: &Path, bytes: &[u8], force: bool) -> Result<(), Error> {
    let file = if force {
        fs::File::create(path)
    } else {
        fs::File::create_new(path)
    };
    file.and_then(|mut f| f.write_all(bytes))
        .map_err(|error| Error::File {
            path: path.display().to_string(),
            error,
        })
}
