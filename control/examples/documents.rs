//! Writes the documents that are generated from the code, so they are never kept in step by
//! hand: `docs/error-codes.md` from [`control::Code::ALL`] (each code's meaning and example
//! are worded in `control/src/report/errors.rs`). Run `cargo run -p control --example documents`
//! after changing an error code; `control/tests/documents.rs` fails until you do.

fn main() {
    let mut text = String::new();
    // Writing to a String cannot fail.
    let _ = control::report::write_error_codes_doc(&mut text);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/error-codes.md");
    if let Err(e) = std::fs::write(path, text) {
        eprintln!("documents: cannot write {path}: {e}");
        std::process::exit(1);
    }
    println!("wrote {path}");
}
