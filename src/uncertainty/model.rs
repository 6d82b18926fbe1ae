//! A named input model: the uncertain vector X of the paper, one marginal per named input.

use super::Marginal;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// One named input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Input {
    /// The input's name, e.g. `wind_speed`.
    pub name: String,
    /// Its distribution.
    #[serde(flatten)]
    pub marginal: Marginal,
}

/// The uncertain inputs in a fixed order; samples are `Vec<f64>` in this order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct InputModel {
    /// The inputs, in sample order.
    pub inputs: Vec<Input>,
}

impl InputModel {
    /// An input model of distinct names and valid marginals.
    pub fn new(inputs: Vec<Input>) -> Result<Self> {
        for (k, input) in inputs.iter().enumerate() {
            if inputs[..k].iter().any(|other| other.name == input.name) {
                return Err(Error::invalid(format!("inputs.{}", input.name), "appears twice"));
            }
            input.marginal.check(&format!("inputs.{}", input.name))?;
        }
        Ok(InputModel { inputs })
    }

    /// Number of inputs.
    pub fn len(&self) -> usize {
        self.inputs.len()
    }

    /// Whether there are no inputs.
    pub fn is_empty(&self) -> bool {
        self.inputs.is_empty()
    }

    /// The input names, in sample order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.inputs.iter().map(|i| i.name.as_str())
    }

    /// Position of a named input, or an error listing the names that exist.
    pub fn index_of(&self, name: &str) -> Result<usize> {
        self.inputs.iter().position(|i| i.name == name).ok_or_else(|| {
            Error::invalid(
                format!("inputs.{name}"),
                format!("unknown input; the inputs are {}", self.names().collect::<Vec<_>>().join(", ")),
            )
        })
    }

    /// The marginal of a named input, or an error listing the names that exist.
    pub fn marginal(&self, name: &str) -> Result<&Marginal> {
        Ok(&self.inputs[self.index_of(name)?].marginal)
    }

    /// Replaces the marginal of a named input (which must exist).
    pub fn with_marginal(mut self, name: &str, marginal: Marginal) -> Result<Self> {
        let k = self.index_of(name)?;
        marginal.check(&format!("inputs.{name}"))?;
        self.inputs[k].marginal = marginal;
        Ok(self)
    }

    /// Holds a named input at `value`, which must lie in the support of its current marginal.
    pub fn with_fixed(self, name: &str, value: f64) -> Result<Self> {
        let marginal = *self.marginal(name)?;
        if !marginal.contains(value) {
            let (lo, hi) = marginal.support();
            return Err(Error::invalid(
                format!("inputs.{name}"),
                format!("value {value} lies outside the support [{lo}, {hi}] of its distribution"),
            ));
        }
        self.with_marginal(name, Marginal::Constant { value })
    }

    /// Every input at its mean.
    pub fn means(&self) -> Vec<f64> {
        self.inputs.iter().map(|i| i.marginal.mean()).collect()
    }

    /// Every input held at its mean.
    pub fn nominal(&self) -> Self {
        let inputs = self
            .inputs
            .iter()
            .map(|i| Input { name: i.name.clone(), marginal: Marginal::Constant { value: i.marginal.mean() } })
            .collect();
        InputModel { inputs }
    }

    /// Maps a physical sample to the standard space, input by input.
    pub fn to_standard(&self, x: &[f64]) -> Vec<f64> {
        self.inputs.iter().zip(x).map(|(i, &v)| i.marginal.to_standard(v)).collect()
    }

    /// Checks that a physical sample has one value per input, each in its marginal's support.
    pub fn check_sample(&self, x: &[f64]) -> Result<()> {
        if x.len() != self.len() {
            return Err(Error::invalid("inputs", format!("expected {} values, got {}", self.len(), x.len())));
        }
        for (input, &v) in self.inputs.iter().zip(x) {
            if !input.marginal.contains(v) {
                let (lo, hi) = input.marginal.support();
                return Err(Error::invalid(
                    format!("inputs.{}", input.name),
                    format!("value {v} lies outside the support [{lo}, {hi}]"),
                ));
            }
        }
        Ok(())
    }
}

/// Parses `NAME=VALUE` as written on a command line.
pub fn parse_assignment(text: &str) -> Result<(String, f64)> {
    let (name, value) =
        text.split_once('=').ok_or_else(|| Error::invalid("fix", format!("expected NAME=VALUE, got `{text}`")))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(Error::invalid("fix", format!("missing input name in `{text}`")));
    }
    let value: f64 = value
        .trim()
        .parse()
        .map_err(|_| Error::invalid(format!("inputs.{name}"), format!("`{}` is not a number", value.trim())))?;
    if !value.is_finite() {
        return Err(Error::invalid(format!("inputs.{name}"), format!("must be finite, got {value}")));
    }
    Ok((name.to_string(), value))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> InputModel {
        InputModel::new(vec![
            Input { name: "a".into(), marginal: Marginal::Lognormal { mean: 1.0, sd: 0.1 } },
            Input { name: "b".into(), marginal: Marginal::Uniform { lower: 0.0, upper: 2.0 } },
        ])
        .unwrap()
    }

    #[test]
    fn fixing_checks_name_and_support() {
        let m = model().with_fixed("b", 1.5).unwrap();
        assert_eq!(m.marginal("b").unwrap(), &Marginal::Constant { value: 1.5 });
        assert!(model().with_fixed("b", 3.0).unwrap_err().to_string().contains("outside the support"));
        assert!(model().with_fixed("a", -1.0).is_err());
        assert!(model().with_fixed("c", 1.0).unwrap_err().to_string().contains("unknown input; the inputs are a, b"));
    }

    #[test]
    fn assignments_parse_or_explain() {
        assert_eq!(parse_assignment("wind_speed=35").unwrap(), ("wind_speed".into(), 35.0));
        assert!(parse_assignment("wind_speed").is_err());
        assert!(parse_assignment("wind_speed=fast").unwrap_err().to_string().contains("not a number"));
        assert!(parse_assignment("=3").is_err());
        assert!(parse_assignment("x=NaN").is_err());
    }

    #[test]
    fn serialises_as_a_list_of_named_marginals() {
        let json = serde_json::to_string(&model()).unwrap();
        assert_eq!(
            json,
            r#"[{"name":"a","distribution":"lognormal","mean":1.0,"sd":0.1},{"name":"b","distribution":"uniform","lower":0.0,"upper":2.0}]"#
        );
        let back: InputModel = serde_json::from_str(&json).unwrap();
        assert_eq!(back, model());
    }
}
