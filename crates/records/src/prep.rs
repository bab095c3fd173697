//! Preprocessing.
use serde::{Deserialize, Serialize};
/// x
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Preprocessing {}
/// x
#[derive(Debug, Clone, Serialize)]
pub struct Applied {}
/// x
pub fn apply() {}
