//! One module per subcommand: its clap arguments beside its handler.

pub(crate) mod backends;
pub(crate) mod compare;
pub(crate) mod diff;
pub(crate) mod info;
pub(crate) mod rays;
pub(crate) mod render;
pub(crate) mod report;
pub(crate) mod scenes;
