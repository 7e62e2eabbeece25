//! With the feature `tinybvh`: compiles `src/tinybvh_shim.cpp`, the C interface of tinybvh's
//! BVH4_CPU and BVH8_CPU that `src/tinybvh.rs` calls, against the `tiny_bvh.h` that the
//! `tinybvh-rs` crate ships. That crate is a dependency for no platform (Cargo.toml): it is
//! pinned by Cargo.lock and downloaded by `cargo fetch`, never compiled, and its Rust API is
//! not used.
//!
//! With the feature `embree`: checks, on Linux, that the linker will find Intel Embree 3
//! (`libembree3.so`, which the `embree` crate links), so that a machine without it gets one
//! line saying what to install instead of a linker error at the end of the build.
//!
//! Without either feature this script does nothing.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "embree")]
    embree::check();
    #[cfg(feature = "tinybvh")]
    tinybvh::compile();
}

#[cfg(feature = "embree")]
mod embree {
    use std::env;
    use std::path::PathBuf;

    /// The library the `embree` crate links (`cargo:rustc-link-lib=embree3`), as the
    /// linker looks for it.
    const LIBRARY: &str = "libembree3.so";

    /// The folders the linker searches: the `embree` crate's `EMBREE_DIR/lib`, those of
    /// `LIBRARY_PATH`, and the system's (Debian's multiarch folder first).
    fn search_dirs() -> Vec<PathBuf> {
        let mut dirs = Vec::new();
        if let Some(dir) = env::var_os("EMBREE_DIR") {
            dirs.push(PathBuf::from(dir).join("lib"));
        }
        if let Some(paths) = env::var_os("LIBRARY_PATH") {
            dirs.extend(env::split_paths(&paths));
        }
        let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
        for dir in [
            format!("/usr/lib/{arch}-linux-gnu"),
            "/usr/local/lib".into(),
            "/usr/lib64".into(),
            "/usr/lib".into(),
            format!("/lib/{arch}-linux-gnu"),
            "/lib64".into(),
            "/lib".into(),
        ] {
            dirs.push(dir.into());
        }
        dirs
    }

    /// Stops the build with one `error:` line when no search folder holds the library.
    /// Other systems are left to their linker.
    pub fn check() {
        println!("cargo:rerun-if-env-changed=EMBREE_DIR");
        println!("cargo:rerun-if-env-changed=LIBRARY_PATH");
        if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("linux") {
            return;
        }
        if let Some(found) = search_dirs()
            .into_iter()
            .map(|d| d.join(LIBRARY))
            .find(|f| f.exists())
        {
            // Checked again if it goes away.
            println!("cargo:rerun-if-changed={}", found.display());
            return;
        }
        eprintln!(
            "error: the feature `embree` needs Intel Embree 3 and no {LIBRARY} was found in \
             EMBREE_DIR/lib, LIBRARY_PATH or the system's library folders: install it \
             (Debian and Ubuntu: apt install libembree-dev) or set EMBREE_DIR to its prefix"
        );
        std::process::exit(1);
    }
}

#[cfg(feature = "tinybvh")]
mod tinybvh {
    use std::env;
    use std::path::{Path, PathBuf};

    /// The `tinybvh-rs` release whose header is compiled (tinybvh 1.6.8), as pinned in the
    /// workspace's Cargo.toml.
    const CRATE_DIR: &str = "tinybvh-rs-0.1.0-beta.3";

    /// Where the crate keeps the header, inside its sources.
    const HEADER_DIR: &str = "ffi/tinybvh";

    /// Overrides the search: a folder holding `tiny_bvh.h` (a vendored or offline setup).
    const OVERRIDE: &str = "RAYBENCH_TINYBVH_DIR";

    /// The folder holding `tiny_bvh.h`: the override, else the `tinybvh-rs` sources cargo
    /// unpacked under `$CARGO_HOME/registry/src/<registry>/`; when they are not there yet,
    /// after `cargo fetch --locked` on this workspace (which downloads every package of
    /// Cargo.lock, for every platform, and compiles nothing).
    fn header_dir() -> Result<PathBuf, String> {
        if let Some(dir) = env::var_os(OVERRIDE) {
            let dir = PathBuf::from(dir);
            return if dir.join("tiny_bvh.h").is_file() {
                Ok(dir)
            } else {
                Err(format!("{OVERRIDE}={} holds no tiny_bvh.h", dir.display()))
            };
        }
        if let Ok(dir) = unpacked() {
            return Ok(dir);
        }
        fetch()?;
        unpacked()
    }

    /// Downloads the packages of Cargo.lock with the cargo running this build (a cargo
    /// since 1.74 lets a download run beside a build: the build holds the package cache's
    /// shared lock only).
    fn fetch() -> Result<(), String> {
        let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let manifest =
            Path::new(&env::var_os("CARGO_MANIFEST_DIR").ok_or("no CARGO_MANIFEST_DIR")?)
                .join("Cargo.toml");
        let status = std::process::Command::new(cargo)
            .args(["fetch", "--locked", "--manifest-path"])
            .arg(&manifest)
            // Cargo reads this script's stdout as instructions: cargo fetch's goes nowhere.
            .stdout(std::process::Stdio::null())
            .status()
            .map_err(|e| format!("cannot run cargo fetch: {e}"))?;
        if status.success() {
            Ok(())
        } else {
            Err(format!(
                "`cargo fetch --locked` failed ({status}) while looking for tiny_bvh.h; set \
                 {OVERRIDE} to a folder holding it for an offline build"
            ))
        }
    }

    /// The header's folder in the unpacked `tinybvh-rs` sources (every registry is searched,
    /// so a mirror works too).
    fn unpacked() -> Result<PathBuf, String> {
        let cargo_home = env::var_os("CARGO_HOME")
            .map(PathBuf::from)
            .or_else(|| env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")))
            .ok_or("neither CARGO_HOME nor HOME is set")?;
        let registries = cargo_home.join("registry").join("src");
        let entries = std::fs::read_dir(&registries)
            .map_err(|e| format!("cannot read {}: {e}", registries.display()))?;
        let mut found: Vec<PathBuf> = entries
            .filter_map(Result::ok)
            .map(|e| e.path().join(CRATE_DIR).join(HEADER_DIR))
            .filter(|d| d.join("tiny_bvh.h").is_file())
            .collect();
        found.sort();
        found.into_iter().next().ok_or_else(|| {
            format!(
                "no {CRATE_DIR}/{HEADER_DIR}/tiny_bvh.h under {} (`cargo fetch` downloads it; \
                 {OVERRIDE} names another folder holding tiny_bvh.h)",
                registries.display()
            )
        })
    }

    pub fn compile() {
        println!("cargo:rerun-if-changed=src/tinybvh_shim.cpp");
        println!("cargo:rerun-if-env-changed={OVERRIDE}");
        // tinybvh's BVH4_CPU and BVH8_CPU kernels are SSE/AVX2 code: on other architectures
        // nothing is compiled and `tinybvh.rs` reports the backends unavailable.
        if env::var("CARGO_CFG_TARGET_ARCH").as_deref() != Ok("x86_64") {
            return;
        }
        let dir = header_dir().unwrap_or_else(|e| panic!("tinybvh: {e}"));
        println!(
            "cargo:rerun-if-changed={}",
            dir.join("tiny_bvh.h").display()
        );
        let mut build = cc::Build::new();
        build
            .cpp(true)
            .std("c++17")
            .file("src/tinybvh_shim.cpp")
            .include(&dir)
            // Third-party code: its warnings are not ours to fix.
            .warnings(false);
        if build.get_compiler().is_like_msvc() {
            build.flag("/arch:AVX2");
        } else {
            // The AVX2 and FMA kernels (BVH8_CPU needs both; BVH4_CPU takes the AVX path).
            build.flag("-mavx2").flag("-mfma").flag("-w");
        }
        build.compile("raybench_tinybvh");
    }
}
