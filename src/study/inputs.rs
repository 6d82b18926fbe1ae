//! The uncertain inputs of a study: the paper's default input model, what each input may be, and
//! a sample read as physical values.

use crate::error::{Error, Result};
use crate::structure::Structure;
use crate::uncertainty::{Input, InputModel, Marginal};

/// The physical values of one sample of the inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalParameters {
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Factor μ on the mass matrix.
    pub mass_factor: f64,
    /// Modal damping ratio ζ, the same for every mode.
    pub damping_ratio: f64,
    /// Coefficient of each damper group (N·(s/m)^α), from the ground up.
    pub damper_coefficients: Vec<f64>,
    /// Mean wind speed at the 10 m station (m/s).
    pub wind_speed: f64,
}

/// A sample's physical parameters: `x` holds a value of every input of `inputs`, by its order.
pub(super) fn physical_parameters(inputs: &InputModel, damper_groups: usize, x: &[f64]) -> Result<PhysicalParameters> {
    inputs.check_sample(x)?;
    let value = |name: &str| -> Result<f64> { Ok(x[inputs.index_of(name)?]) };
    let damper_coefficients =
        (1..=damper_groups).map(|g| value(&format!("damper_c{g}"))).collect::<Result<Vec<_>>>()?;
    Ok(PhysicalParameters {
        youngs_modulus: value("youngs_modulus")?,
        mass_factor: value("mass_factor")?,
        damping_ratio: value("damping_ratio")?,
        damper_coefficients,
        wind_speed: value(WIND_SPEED)?,
    })
}

/// The paper's input model (section 4.3) for `structure`; damper coefficients uniform on
/// [0, 100·damper_scale].
pub(super) fn default_inputs(structure: &Structure, damper_scale: f64) -> InputModel {
    frame_inputs(structure.reference_youngs_modulus, structure.damper_groups(), damper_scale)
}

/// The paper's input model for a building of reference modulus `youngs_modulus` (Pa) with
/// `damper_groups` coefficient groups.
pub(super) fn frame_inputs(youngs_modulus: f64, damper_groups: usize, damper_scale: f64) -> InputModel {
    let mut inputs = vec![
        Input {
            name: "youngs_modulus".into(),
            marginal: Marginal::Lognormal { mean: youngs_modulus, sd: youngs_modulus * 15.0 / 210.0 },
        },
        Input { name: "mass_factor".into(), marginal: Marginal::Lognormal { mean: 1.0, sd: 0.05 } },
        Input { name: "damping_ratio".into(), marginal: Marginal::Lognormal { mean: 0.015, sd: 0.005 } },
    ];
    for g in 0..damper_groups {
        inputs.push(Input {
            name: format!("damper_c{}", g + 1),
            marginal: Marginal::Uniform { lower: 0.0, upper: 100.0 * damper_scale },
        });
    }
    inputs.push(Input { name: WIND_SPEED.into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } });
    InputModel { inputs }
}

/// The storm's mean wind speed at the 10 m station (m/s): the input that the load scales with,
/// that annual analyses replace by a climate, and whose germ the metamodel treats apart.
pub const WIND_SPEED: &str = "wind_speed";

/// The wind's direction (degrees): where it blows towards, counter-clockwise from the plan's x
/// axis; an input of a three-dimensional study like the speed, uniform around the circle unless
/// the spec says otherwise.
pub const WIND_DIRECTION: &str = "wind_direction";

/// Inputs that are angles (degrees), any real value.
const ANGULAR_INPUTS: [&str; 1] = [WIND_DIRECTION];

/// Every other physical input is non-negative; these must also stay away from zero.
const POSITIVE_INPUTS: [&str; 3] = ["youngs_modulus", "mass_factor", WIND_SPEED];

/// Probability below which a marginal's mass under zero is no objection: a Gumbel law of annual
/// maximum speeds, unbounded below, puts exp(−e^(μ/β)) there (10⁻⁴³ for Gumbel(22, 2.2)), and a
/// Latin hypercube or a sampling never reaches it.
const NEGLIGIBLE_PROBABILITY: f64 = 1e-12;

/// Refuses a marginal that reaches values the input cannot take with more than a negligible
/// probability.
pub(super) fn check_admissible(input: &Input) -> Result<()> {
    // A direction is an angle: any value is one, −30° being 330°.
    if ANGULAR_INPUTS.contains(&input.name.as_str()) {
        return Ok(());
    }
    let (lower, _) = input.marginal.support();
    let positive = POSITIVE_INPUTS.contains(&input.name.as_str());
    let below_zero = lower < 0.0 && input.marginal.cdf(0.0) > NEGLIGIBLE_PROBABILITY;
    let at_zero = positive && lower >= 0.0 && input.marginal.contains(0.0);
    if below_zero || at_zero {
        let bound = if positive { "positive" } else { "non-negative" };
        return Err(Error::invalid(
            format!("inputs.{}", input.name),
            format!(
                "must be {bound}, but its distribution reaches {lower} (with probability {:.1e} below 0); choose one \
                 that stays {bound} but for a probability of 10⁻¹² at most (lognormal, uniform, a Gumbel far from 0)",
                input.marginal.cdf(0.0)
            ),
        ));
    }
    Ok(())
}
