//! The scene's `transmission_loss` key: how `--tl` and the transmission-loss calls sum the
//! arrivals at each receiver.

use serde::{Deserialize, Serialize};

use super::{SceneError, SceneSpec};

/// How arrivals add up to a transmission loss (`transmission_loss.mode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TransmissionLossMode {
    /// The pressure with its phases: `p = Σ a · e^(iωT)` (the default).
    #[default]
    Coherent,
    /// The intensities, phases left out: `|p|² = Σ |a|²`.
    Incoherent,
}

impl TransmissionLossMode {
    /// The mode's name in the document.
    pub fn as_str(self) -> &'static str {
        match self {
            TransmissionLossMode::Coherent => "coherent",
            TransmissionLossMode::Incoherent => "incoherent",
        }
    }
}

/// The `transmission_loss` section.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransmissionLossSpec {
    /// `"coherent"` (the default) or `"incoherent"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<TransmissionLossMode>,
}

impl TransmissionLossSpec {
    /// A section with `mode`.
    pub fn new(mode: TransmissionLossMode) -> TransmissionLossSpec {
        TransmissionLossSpec { mode: Some(mode) }
    }
}

/// Validates the scene's `transmission_loss` section, which needs `amplitudes` with a
/// `frequency`: its mode, when the scene gives one.
pub(super) fn validate(spec: &SceneSpec) -> Result<Option<TransmissionLossMode>, SceneError> {
    let Some(tl) = &spec.transmission_loss else {
        return Ok(None);
    };
    if spec.amplitudes.and_then(|a| a.frequency).is_none() {
        return Err(SceneError::new(
            "transmission_loss",
            "needs `amplitudes` with a `frequency` (the loss is at one frequency): add \
             \"amplitudes\": {\"source\": \"point\", \"frequency\": 100} or another",
        ));
    }
    Ok(Some(tl.mode.unwrap_or_default()))
}

#[cfg(test)]
mod tests {
    use crate::Scene;

    fn scene(extra: &str) -> Result<Scene, crate::SceneError> {
        Scene::from_json(&format!(
            r#"{{ "media": {{ "w": {{ "speed": 1500 }} }}, "sources": [[0, 0]],
                 "receivers": [[1, 0]], "paths": [{{ "steps": [] }}] {extra} }}"#
        ))
    }

    #[test]
    fn the_mode_is_read_and_defaults_to_coherent() {
        let f = r#", "amplitudes": { "source": "point", "frequency": 100 }"#;
        assert_eq!(scene(f).unwrap().transmission_loss(), None);
        let c = scene(&format!(r#"{f}, "transmission_loss": {{}}"#)).unwrap();
        assert_eq!(
            c.transmission_loss(),
            Some(super::TransmissionLossMode::Coherent)
        );
        let i = scene(&format!(
            r#"{f}, "transmission_loss": {{ "mode": "incoherent" }}"#
        ));
        assert_eq!(
            i.unwrap().transmission_loss(),
            Some(super::TransmissionLossMode::Incoherent)
        );
    }

    #[test]
    fn bad_sections_name_their_key() {
        let no_frequency = r#", "amplitudes": { "source": "point" }, "transmission_loss": {}"#;
        assert_eq!(scene(no_frequency).unwrap_err().key, "transmission_loss");
        let no_amplitudes = r#", "transmission_loss": { "mode": "coherent" }"#;
        assert_eq!(scene(no_amplitudes).unwrap_err().key, "transmission_loss");
        let f = r#", "amplitudes": { "source": "point", "frequency": 100 }"#;
        let typo = scene(&format!(
            r#"{f}, "transmission_loss": {{ "mode": "coherant" }}"#
        ));
        assert!(typo.unwrap_err().to_string().contains("transmission_loss"));
    }
}
