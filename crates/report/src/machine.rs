//! The machine description at the top of every report.

use crate::results::{Caches, Machine};
use raybench_registry::Roles;

/// Describes this machine; `threads` is the worker count used for rendering.
#[must_use]
pub fn describe(threads: usize) -> Machine {
    Machine {
        host: host(),
        cpu: cpu_model(),
        cores: std::thread::available_parallelism().map_or(1, std::num::NonZero::get),
        threads,
        isa: isa(),
        gpu: gpu(),
        os: os(),
        version: version(),
        build: raybench_registry::BUILD.to_string(),
        frequency: frequency(),
        smt: smt(),
        caches: caches(),
    }
}

/// This machine's data caches (CPU 0's), where Linux describes them.
#[must_use]
pub fn caches() -> Option<Caches> {
    caches_in(std::path::Path::new(CACHE_DIR))
}

/// Where Linux describes CPU 0's caches: one `index*` folder per cache, with its `level`,
/// `type` and `size`.
const CACHE_DIR: &str = "/sys/devices/system/cpu/cpu0/cache";

/// A sysfs cache size (`48K`, `2048K`, `32M`, or plain bytes) in bytes.
fn cache_bytes(size: &str) -> Option<u64> {
    let size = size.trim();
    let (digits, unit) = match size.char_indices().find(|(_, c)| !c.is_ascii_digit()) {
        Some((i, _)) => size.split_at(i),
        None => (size, ""),
    };
    let scale = match unit.trim() {
        "" => 1,
        "K" | "KB" | "KiB" => 1 << 10,
        "M" | "MB" | "MiB" => 1 << 20,
        "G" | "GB" | "GiB" => 1 << 30,
        _ => return None,
    };
    digits.parse::<u64>().ok()?.checked_mul(scale)
}

/// The data caches described under `dir` (the layout of [`CACHE_DIR`]): per level 1 to 3,
/// the data or unified cache's size (instruction caches are left out); `None` when no level
/// is known.
fn caches_in(dir: &std::path::Path) -> Option<Caches> {
    let mut caches = Caches::default();
    let mut entries: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("index"))
        })
        .collect();
    entries.sort();
    for index in entries {
        let read = |file: &str| sysfs(&index.join(file).to_string_lossy());
        let (Some(level), Some(kind), Some(size)) = (read("level"), read("type"), read("size"))
        else {
            continue;
        };
        if kind == "Instruction" {
            continue;
        }
        let slot = match level.as_str() {
            "1" => &mut caches.l1d,
            "2" => &mut caches.l2,
            "3" => &mut caches.l3,
            _ => continue,
        };
        if slot.is_none() {
            *slot = cache_bytes(&size);
        }
    }
    (caches != Caches::default()).then_some(caches)
}

/// The value of the first line of `/proc/cpuinfo` whose key is `key`, trimmed.
fn cpuinfo(key: &str) -> Option<String> {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| cpuinfo_field(&s, key))
}

/// The value of the first `key : value` line of `/proc/cpuinfo`'s text whose key is exactly
/// `key` (`model` is not `model name`).
fn cpuinfo_field(text: &str, key: &str) -> Option<String> {
    text.lines()
        .filter_map(|l| l.split_once(':'))
        .find(|(k, _)| k.trim() == key)
        .map(|(_, v)| v.trim().to_string())
}

/// The contents of a sysfs file, trimmed; `None` when it is missing or empty.
fn sysfs(path: &str) -> Option<String> {
    std::fs::read_to_string(path)
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
}

/// The frequency policy of CPU 0: `governor performance, 1500-3700 MHz` where the OS
/// manages the frequency (`cpufreq`); otherwise the frequency `/proc/cpuinfo` reports and
/// why nothing more is known (a virtual machine's guest, or firmware that decides alone).
fn frequency() -> String {
    let base = "/sys/devices/system/cpu/cpu0/cpufreq";
    let mhz = |file: &str| {
        sysfs(&format!("{base}/{file}"))
            .and_then(|k| k.parse::<u64>().ok())
            .map(|khz| khz / 1000)
    };
    if let Some(governor) = sysfs(&format!("{base}/scaling_governor")) {
        let range = match (mhz("scaling_min_freq"), mhz("scaling_max_freq")) {
            (Some(lo), Some(hi)) => format!(", {lo}-{hi} MHz"),
            _ => String::new(),
        };
        let boost = sysfs("/sys/devices/system/cpu/cpufreq/boost")
            .map(|b| format!(", boost {}", if b == "1" { "on" } else { "off" }))
            .unwrap_or_default();
        return format!("governor {governor}{range}{boost}");
    }
    let reported = cpuinfo("cpu MHz")
        .and_then(|m| m.parse::<f64>().ok())
        .map_or_else(String::new, |m| format!("{m:.0} MHz reported; "));
    format!(
        "{reported}no cpufreq policy exposed (a virtual machine's guest, or the firmware decides)"
    )
}

/// Simultaneous multithreading: `off (1 thread per core)`, `on (2 threads per core)`, or
/// what the OS says where it cannot tell (`notsupported`: a guest that sees no siblings).
fn smt() -> String {
    let per_core =
        sysfs("/sys/devices/system/cpu/cpu0/topology/thread_siblings_list").map(|list| {
            list.split(',')
                .map(|part| match part.split_once('-') {
                    Some((a, b)) => match (a.parse::<u32>(), b.parse::<u32>()) {
                        (Ok(a), Ok(b)) if b >= a => b - a + 1,
                        _ => 1,
                    },
                    None => 1,
                })
                .sum::<u32>()
        });
    let control = sysfs("/sys/devices/system/cpu/smt/control");
    let active = sysfs("/sys/devices/system/cpu/smt/active");
    let threads = per_core.map_or_else(String::new, |n| {
        format!(" ({n} thread{} per core)", if n == 1 { "" } else { "s" })
    });
    match (active.as_deref(), control.as_deref()) {
        (Some("1"), _) => format!("on{threads}"),
        (_, Some("notsupported" | "notimplemented")) => {
            format!("not supported as the OS sees the CPU{threads}")
        }
        (Some("0"), _) => format!("off{threads}"),
        _ => format!("unknown{threads}"),
    }
}

/// The adapter the registry's device backend ([`Roles::DEVICE`]) uses, or why there is none.
fn gpu() -> String {
    let Some(b) = raybench_registry::with_role(Roles::DEVICE) else {
        return "none (no device backend registered)".into();
    };
    let r = (b.make)();
    match (r.device(), r.availability()) {
        (Some(d), _) => d,
        (None, Err(why)) => format!("none ({why})"),
        (None, Ok(())) => "unknown".into(),
    }
}

/// The host name the kernel reports (on a cluster, the node's name), or `unknown`.
fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| cpu_model_in(&s))
        .unwrap_or_else(|| format!("unknown ({})", std::env::consts::ARCH))
}

/// The model name in `/proc/cpuinfo`'s text, with the x86 family and model numbers where it
/// gives them: a virtual machine's guest often sees a bare `AMD EPYC` for CPUs of different
/// generations (with different caches and instruction sets), whose timings do not compare.
fn cpu_model_in(text: &str) -> Option<String> {
    let name = cpuinfo_field(text, "model name")?;
    Some(
        match (
            cpuinfo_field(text, "cpu family"),
            cpuinfo_field(text, "model"),
        ) {
            (Some(family), Some(model)) => format!("{name} (family {family}, model {model})"),
            _ => name,
        },
    )
}

/// What the backends with a [`raybench_registry::Backend::detail`] chose (the packet backend's
/// instruction set), and the CPU's SIMD extensions.
fn isa() -> String {
    let chosen: Vec<String> = raybench_registry::BACKENDS
        .iter()
        .filter(|b| !b.is(Roles::PINNED))
        .filter_map(|b| b.detail.map(|d| format!("{} backend uses {}", b.name, d())))
        .collect();
    #[cfg(target_arch = "x86_64")]
    let extensions: Vec<&str> = [
        ("sse4.1", std::arch::is_x86_feature_detected!("sse4.1")),
        ("avx2", std::arch::is_x86_feature_detected!("avx2")),
        ("fma", std::arch::is_x86_feature_detected!("fma")),
        ("avx512f", std::arch::is_x86_feature_detected!("avx512f")),
    ]
    .into_iter()
    .filter_map(|(n, on)| on.then_some(n))
    .collect();
    #[cfg(not(target_arch = "x86_64"))]
    let extensions: Vec<&str> = Vec::new();
    format!(
        "{}; CPU has {}",
        if chosen.is_empty() {
            "no SIMD backend".to_string()
        } else {
            chosen.join(", ")
        },
        if extensions.is_empty() {
            "no x86 SIMD extensions".to_string()
        } else {
            extensions.join(", ")
        }
    )
}

fn os() -> String {
    let pretty = std::fs::read_to_string("/etc/os-release")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("PRETTY_NAME="))
                .map(|v| v.trim_matches('"').to_string())
        });
    let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease")
        .ok()
        .map(|s| s.trim().to_string());
    match (pretty, kernel) {
        (Some(p), Some(k)) => format!("{p}, Linux {k}"),
        (Some(p), None) => p,
        (None, Some(k)) => format!("Linux {k}"),
        (None, None) => std::env::consts::OS.to_string(),
    }
}

/// `raybench VERSION (REVISION)`: the revision recorded at build time, so that the report
/// names the code that measured, whatever the current directory is.
fn version() -> String {
    format!("raybench {}", raybench_registry::VERSION)
}

/// The current UTC time as RFC 3339 (`2026-11-23T02:44:30Z`), from the system clock.
#[must_use]
pub fn now_utc() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (y, m, d) = civil_from_days(days as i64);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Proleptic Gregorian date of the day `days` after 1970-01-01 (Howard Hinnant's
/// `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CPU is named with its family and model where `/proc/cpuinfo` gives them, and a
    /// key is matched whole (`model` is not `model name`).
    #[test]
    fn the_cpu_is_named_with_its_family_and_model() {
        let x86 = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\n\
                   model\t\t: 1\nmodel name\t: AMD EPYC\nstepping\t: 1\n";
        assert_eq!(
            cpu_model_in(x86).as_deref(),
            Some("AMD EPYC (family 25, model 1)")
        );
        assert_eq!(cpuinfo_field(x86, "model").as_deref(), Some("1"));
        let bare = "processor\t: 0\nmodel name\t: Some CPU\n";
        assert_eq!(cpu_model_in(bare).as_deref(), Some("Some CPU"));
        assert_eq!(cpu_model_in("processor\t: 0\n"), None);
    }

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(19_723), (2024, 1, 1));
        assert_eq!(civil_from_days(20_415), (2025, 11, 23));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
    }

    /// Sizes in sysfs's forms; anything else is unknown.
    #[test]
    fn cache_sizes_parse() {
        assert_eq!(cache_bytes("48K"), Some(48 * 1024));
        assert_eq!(cache_bytes("2048K\n"), Some(2 << 20));
        assert_eq!(cache_bytes("32M"), Some(32 << 20));
        assert_eq!(cache_bytes("512"), Some(512));
        assert_eq!(cache_bytes("1G"), Some(1 << 30));
        assert_eq!(cache_bytes("12X"), None);
        assert_eq!(cache_bytes(""), None);
    }

    /// A fake sysfs folder: the data and unified caches by level, the instruction cache and
    /// a fourth level left out, a folder without its files skipped; none at all is `None`.
    #[test]
    fn caches_are_read_from_sysfs() {
        let dir = std::env::temp_dir().join(format!("raybench-caches-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let index = |i: u32, level: &str, kind: &str, size: &str| {
            let d = dir.join(format!("index{i}"));
            std::fs::create_dir_all(&d).unwrap();
            for (file, text) in [("level", level), ("type", kind), ("size", size)] {
                std::fs::write(d.join(file), format!("{text}\n")).unwrap();
            }
        };
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(caches_in(&dir), None);
        index(0, "1", "Data", "48K");
        index(1, "1", "Instruction", "64K");
        index(2, "2", "Unified", "2048K");
        index(3, "3", "Unified", "491520K");
        index(4, "4", "Unified", "1G");
        std::fs::create_dir_all(dir.join("index5")).unwrap();
        std::fs::create_dir_all(dir.join("power")).unwrap();
        assert_eq!(
            caches_in(&dir),
            Some(Caches {
                l1d: Some(48 << 10),
                l2: Some(2 << 20),
                l3: Some(480 << 20),
            })
        );
        assert_eq!(caches_in(&dir.join("missing")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn machine_is_described() {
        let m = describe(2);
        assert!(!m.cpu.is_empty() && m.cores >= 1 && m.threads == 2);
        assert!(!m.host.is_empty());
        assert!(m.isa.contains("lanes"));
        assert!(m.build.starts_with("rustc ") && m.build.contains("opt-level"));
        assert!(!m.frequency.is_empty() && !m.smt.is_empty());
        assert!(now_utc().ends_with('Z'));
    }
}
