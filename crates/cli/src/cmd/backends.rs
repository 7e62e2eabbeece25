//! `raybench backends`: the registry's backends, their presets and availability.

use anyhow::Result;
use raybench_registry::{BACKENDS, NOT_BUILT};
use serde::Serialize;
use std::process::ExitCode;

#[derive(Serialize)]
pub(crate) struct BackendRow {
    pub(crate) name: &'static str,
    /// For a build preset (`bvh:fast`): the backend it builds, and whether it is that
    /// backend's default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) preset_of: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) default_preset: Option<bool>,
    pub(crate) available: bool,
    pub(crate) reason: Option<String>,
    pub(crate) exact: bool,
    /// Its roles in the registry (`exact`, `oracle`, `brute-force`, `pinned`, `peer`, ...).
    pub(crate) roles: Vec<&'static str>,
    pub(crate) description: &'static str,
    /// The device it runs on when that is not this CPU (the GPU adapter).
    pub(crate) device: Option<String>,
}

pub(crate) fn backends(json: bool) -> Result<ExitCode> {
    let row = |b: &'static raybench_registry::Backend, preset: Option<(&'static str, bool)>| {
        let r = (b.make)();
        let avail = r.availability();
        BackendRow {
            name: b.name,
            preset_of: preset.map(|p| p.0),
            default_preset: preset.map(|p| p.1),
            available: avail.is_ok(),
            reason: avail.err(),
            exact: b.exact(),
            roles: b.roles.names(),
            description: b.description,
            device: r.device(),
        }
    };
    let built = BACKENDS.iter().map(|b| row(b, None));
    let presets = raybench_registry::presets::PRESETS
        .iter()
        .map(|p| row(&p.entry, Some((p.backend, p.default))));
    let not_built = NOT_BUILT.iter().map(|n| BackendRow {
        name: n.name,
        preset_of: None,
        default_preset: None,
        available: false,
        reason: Some(n.reason()),
        exact: false,
        roles: Vec::new(),
        description: n.description,
        device: None,
    });
    let rows: Vec<BackendRow> = built.chain(not_built).chain(presets).collect();
    if json {
        outln!("{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        let width = rows
            .iter()
            .map(|r| r.name.len() + 2)
            .max()
            .unwrap_or(0)
            .max(16);
        let mut presets_begun = false;
        for r in rows {
            if r.preset_of.is_some() && !presets_begun {
                presets_begun = true;
                outln!(
                    "\nBuild presets (name them as BACKEND:PRESET wherever a backend is taken; \
                     * = the backend's default):"
                )?;
            }
            let name = match r.default_preset {
                Some(true) => format!("{}*", r.name),
                _ => r.name.to_string(),
            };
            let state = if r.available {
                "available".to_string()
            } else {
                format!("unavailable ({})", r.reason.unwrap_or_default())
            };
            outln!("{name:<width$} {:<12} {}", state, r.description)?;
            if let Some(d) = &r.device {
                outln!("{:<width$} {:<12} device: {d}", "", "")?;
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
