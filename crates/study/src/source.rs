//! Where a configuration comes from: a RON file, RON text, a JSON-like value (a Python
//! dict), or the embedded default (R1, `examples/r1-maxwell.ron`), with `--set` overrides.

use std::path::PathBuf;

use anyhow::Context as _;

use crate::config::{self, Config};
use crate::error::{Classify, ErrorKind, Result};

/// The default problem of `identify` without a configuration: R1.
pub const DEFAULT_CONFIG: &str = include_str!("../../../examples/r1-maxwell.ron");
/// Its name in messages.
pub const DEFAULT_NAME: &str = "examples/r1-maxwell.ron (embedded default)";

/// A configuration to load.
#[derive(Clone, Debug, PartialEq)]
pub enum ConfigSource {
    /// A RON file; relative `data.file` paths are found from its folder.
    Path(PathBuf),
    /// RON text called `name` in messages; relative data paths from the working directory.
    Text {
        /// The RON text.
        text: String,
        /// Its name in messages.
        name: String,
    },
    /// The same structure as a value (the RON file's fields as keys; enum variants as
    /// `{"Cylinder": {...}}` or `"Vertical"`), called `name` in messages.
    Value {
        /// The value.
        value: serde_json::Value,
        /// Its name in messages.
        name: String,
    },
    /// The embedded default, [`DEFAULT_CONFIG`].
    Default,
}

impl ConfigSource {
    /// The name used in messages: the file's path, or the given name.
    pub fn name(&self) -> String {
        match self {
            ConfigSource::Path(p) => p.display().to_string(),
            ConfigSource::Text { name, .. } | ConfigSource::Value { name, .. } => name.clone(),
            ConfigSource::Default => DEFAULT_NAME.to_string(),
        }
    }

    /// Reads, overrides (`sets`, each `dotted.path=value`) and validates the configuration.
    ///
    /// # Errors
    /// A [`ErrorKind::Config`] error naming the file, line, field and what is allowed.
    pub fn load(&self, sets: &[String]) -> Result<Config> {
        match self {
            ConfigSource::Path(p) => config::load(p, sets),
            ConfigSource::Text { text, name } => config::load_str(text, name, sets),
            ConfigSource::Default => config::load_str(DEFAULT_CONFIG, DEFAULT_NAME, sets),
            ConfigSource::Value { value, name } => (|| {
                let cfg: Config = serde_json::from_value(value.clone())
                    .map_err(|e| anyhow::anyhow!("{e}"))
                    .with_context(|| format!("cannot read the configuration `{name}`"))?;
                let stated = config::StatedModel::of_value(value).with_sets(sets);
                let mut cfg = config::apply_sets(cfg, sets)?;
                cfg.resolve_model_defaults(stated);
                cfg.validate()
                    .with_context(|| format!("invalid configuration `{name}`"))?;
                Ok::<_, anyhow::Error>(cfg)
            })(),
        }
        .kind(ErrorKind::Config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_source_gives_the_same_configuration() {
        let from_text = ConfigSource::Text {
            text: DEFAULT_CONFIG.into(),
            name: "r1".into(),
        }
        .load(&[])
        .unwrap();
        let from_default = ConfigSource::Default.load(&[]).unwrap();
        assert_eq!(from_text, from_default);
        let value = serde_json::to_value(&from_text).unwrap();
        let from_value = ConfigSource::Value {
            value,
            name: "dict".into(),
        }
        .load(&["law.E=25000".into()])
        .unwrap();
        assert_eq!(from_value.law.named_params()[0], ("E", 25000.0));
    }

    #[test]
    fn an_unknown_key_in_a_value_is_named() {
        let mut value = serde_json::to_value(ConfigSource::Default.load(&[]).unwrap()).unwrap();
        value["solver"]["residual_tolerance"] = 1e-9.into();
        let e = ConfigSource::Value {
            value,
            name: "dict".into(),
        }
        .load(&[])
        .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Config);
        let all = e.messages().join("\n");
        assert!(all.contains("residual_tolerance"), "{all}");
    }
}
