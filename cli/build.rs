//! Embeds the 3D view's page (`emulator/view/`: its HTML, scripts and styles, the same files
//! `./dev run`'s server serves) into the tool, for `hexapod view`: an installed tool serves the
//! page of its own version. Writes `$OUT_DIR/view_page.rs`, a table `(name, bytes)`.

use std::fmt::Write as _;
use std::path::Path;
use std::{env, fs};

fn main() {
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let page = Path::new(&manifest)
        .join("..")
        .join("emulator")
        .join("view");
    println!("cargo:rerun-if-changed={}", page.display());
    let mut files: Vec<_> = fs::read_dir(&page)
        .map(|dir| dir.filter_map(Result::ok).map(|e| e.path()).collect())
        .unwrap_or_default();
    files.sort();
    let mut table = String::from("/// The page's files: name (under /view/) and contents.\n");
    table.push_str("pub const PAGE: &[(&str, &[u8])] = &[\n");
    for path in files {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        // The page's own text files; not the README's picture.
        let served = [".html", ".js", ".css"]
            .iter()
            .any(|ext| name.ends_with(ext));
        if !served || !path.is_file() {
            continue;
        }
        println!("cargo:rerun-if-changed={}", path.display());
        let _ = writeln!(
            table,
            "    ({name:?}, include_bytes!({:?})),",
            path.display().to_string()
        );
    }
    table.push_str("];\n");
    let out = Path::new(&env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("view_page.rs");
    fs::write(out, table).expect("OUT_DIR is writable");
}
