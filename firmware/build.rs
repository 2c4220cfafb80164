//! Puts the workspace's `memory.x` where the linker finds it and hands the linker scripts to
//! the firmware binary only (never to host builds or tests of other crates).

use std::{env, fs, path::PathBuf};

fn main() {
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory_x =
        fs::read("../memory.x").expect("../memory.x (the RP2040 memory map) is readable");
    fs::write(out_dir.join("memory.x"), memory_x).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out_dir.display());
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=build.rs");

    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
