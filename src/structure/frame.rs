//! A plane steel moment frame by beam-column finite elements, with rigid floors, statically condensed
//! to one lateral degree of freedom per floor.
//!
//! Every node has a horizontal, a vertical and a rotational degree of freedom; the rigid floor ties
//! the horizontal ones of a level into one. The vertical and rotational degrees of freedom carry no
//! mass, so condensing them out (K_c = K_ll − K_lo K_oo⁻¹ K_ol) is exact for the dynamics.

use super::{DamperPlacement, Section, Structure};
use crate::error::{Error, Result};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

/// The members of one storey: the columns below a floor and the beams of that floor.
#[derive(Debug, Clone, Copy)]
pub struct StoreySections {
    /// The beams of the floor.
    pub beam: Section,
    /// The two outer column lines.
    pub exterior_column: Section,
    /// The inner column lines.
    pub interior_column: Section,
}

/// Geometry, material and loads of a regular plane frame with one diagonal damper per storey.
#[derive(Debug, Clone)]
pub struct FrameSpec {
    /// Width of each bay (m), left to right.
    pub bay_widths: Vec<f64>,
    /// Storey heights from the ground up (m); storey j lies below floor j.
    pub storey_heights: Vec<f64>,
    /// The members of each storey, from the ground up.
    pub storeys: Vec<StoreySections>,
    /// Young's modulus of the steel (Pa).
    pub youngs_modulus: f64,
    /// Density of the steel (kg/m³): the members' own mass.
    pub steel_density: f64,
    /// Dead load carried by a floor per metre of floor length and per metre of the storey height
    /// below it (N/m²): the paper's q₀ = 11.96·h_j kN/m.
    pub dead_load_per_storey_height: f64,
    /// Acceleration of gravity (m/s²), which turns the dead load into floor mass.
    pub gravity: f64,
    /// Façade width exposed to the wind (m).
    pub wind_width: f64,
    /// Storeys per damper coefficient group.
    pub storeys_per_damper_group: usize,
    /// Width of the bay holding the diagonal dampers (m).
    pub damper_bay_width: f64,
}

impl FrameSpec {
    fn column_lines(&self) -> usize {
        self.bay_widths.len() + 1
    }

    fn floor_length(&self) -> f64 {
        self.bay_widths.iter().sum()
    }

    /// Assembles, condenses and lumps the masses; returns the lateral [`Structure`].
    pub fn build(&self) -> Result<Structure> {
        let floors = self.storey_heights.len();
        if self.storeys.len() != floors {
            return Err(Error::invalid("storeys", "one set of sections per storey is needed"));
        }
        let stiffness = self.condensed_stiffness()?;
        let masses = self.floor_masses();
        let mass = Mat::from_fn(floors, floors, |i, j| if i == j { masses[i] } else { 0.0 });
        let mut elevations = Vec::with_capacity(floors);
        let mut z = 0.0;
        for h in &self.storey_heights {
            z += h;
            elevations.push(z);
        }
        let dampers = self
            .storey_heights
            .iter()
            .enumerate()
            .map(|(j, &h)| DamperPlacement {
                lower_floor: j.checked_sub(1),
                upper_floor: j,
                cos_angle: self.damper_bay_width / self.damper_bay_width.hypot(h),
                group: j / self.storeys_per_damper_group,
            })
            .collect();
        Structure::new(stiffness, mass, elevations, vec![self.wind_width; floors], self.youngs_modulus, dampers)
    }

    /// Lumped floor mass (kg): carried dead load q₀·L/g plus the steel of the floor's beams and half
    /// of the columns above and below.
    pub fn floor_masses(&self) -> Vec<f64> {
        let floors = self.storey_heights.len();
        let column_steel = |storey: usize| -> f64 {
            let s = &self.storeys[storey];
            let lines = self.column_lines();
            let area = 2.0 * s.exterior_column.area + (lines - 2) as f64 * s.interior_column.area;
            area * self.storey_heights[storey] * self.steel_density
        };
        (0..floors)
            .map(|j| {
                let h = self.storey_heights[j];
                let carried = self.dead_load_per_storey_height * h * self.floor_length() / self.gravity;
                let beams = self.storeys[j].beam.area * self.floor_length() * self.steel_density;
                let above = if j + 1 < floors { column_steel(j + 1) } else { 0.0 };
                carried + beams + 0.5 * (column_steel(j) + above)
            })
            .collect()
    }

    /// Global index of each node's (horizontal, vertical, rotation) degree of freedom; the ground is
    /// fixed (`None`). Lateral DOFs come first, one per floor.
    fn dof(&self, level: usize, line: usize) -> [Option<usize>; 3] {
        if level == 0 {
            return [None; 3];
        }
        let floors = self.storey_heights.len();
        let base = floors + ((level - 1) * self.column_lines() + line) * 2;
        [Some(level - 1), Some(base), Some(base + 1)]
    }

    fn condensed_stiffness(&self) -> Result<Mat<f64>> {
        let floors = self.storey_heights.len();
        let lines = self.column_lines();
        let total = floors + floors * lines * 2;
        let mut k = Mat::<f64>::zeros(total, total);
        let e = self.youngs_modulus;
        let x: Vec<f64> = std::iter::once(0.0)
            .chain(self.bay_widths.iter().scan(0.0, |acc, w| {
                *acc += w;
                Some(*acc)
            }))
            .collect();
        for storey in 0..floors {
            let h = self.storey_heights[storey];
            let s = &self.storeys[storey];
            for line in 0..lines {
                let section = if line == 0 || line == lines - 1 { s.exterior_column } else { s.interior_column };
                let element = element_stiffness(e, section, h, 0.0, 1.0);
                scatter(&mut k, &element, self.dof(storey, line), self.dof(storey + 1, line));
            }
            for bay in 0..lines - 1 {
                let element = element_stiffness(e, s.beam, x[bay + 1] - x[bay], 1.0, 0.0);
                scatter(&mut k, &element, self.dof(storey + 1, bay), self.dof(storey + 1, bay + 1));
            }
        }
        condense(&k, floors)
    }
}

/// Euler-Bernoulli beam-column element in global coordinates; (c, s) is the direction of its axis.
fn element_stiffness(e: f64, section: Section, length: f64, c: f64, s: f64) -> [[f64; 6]; 6] {
    let (l, a, i) = (length, section.area, section.inertia);
    let ea = e * a / l;
    let k = e * i / l.powi(3);
    let local = [
        [ea, 0.0, 0.0, -ea, 0.0, 0.0],
        [0.0, 12.0 * k, 6.0 * k * l, 0.0, -12.0 * k, 6.0 * k * l],
        [0.0, 6.0 * k * l, 4.0 * k * l * l, 0.0, -6.0 * k * l, 2.0 * k * l * l],
        [-ea, 0.0, 0.0, ea, 0.0, 0.0],
        [0.0, -12.0 * k, -6.0 * k * l, 0.0, 12.0 * k, -6.0 * k * l],
        [0.0, 6.0 * k * l, 2.0 * k * l * l, 0.0, -6.0 * k * l, 4.0 * k * l * l],
    ];
    // T maps global (X, Y, θ) to local (axial, transverse, θ) at each end.
    let mut t = [[0.0; 6]; 6];
    for end in 0..2 {
        let o = 3 * end;
        t[o][o] = c;
        t[o][o + 1] = s;
        t[o + 1][o] = -s;
        t[o + 1][o + 1] = c;
        t[o + 2][o + 2] = 1.0;
    }
    let mut global = [[0.0; 6]; 6];
    for p in 0..6 {
        for q in 0..6 {
            let mut sum = 0.0;
            for r in 0..6 {
                for u in 0..6 {
                    sum += t[r][p] * local[r][u] * t[u][q];
                }
            }
            global[p][q] = sum;
        }
    }
    global
}

fn scatter(k: &mut Mat<f64>, element: &[[f64; 6]; 6], start: [Option<usize>; 3], end: [Option<usize>; 3]) {
    let dofs: Vec<Option<usize>> = start.into_iter().chain(end).collect();
    for (p, dp) in dofs.iter().enumerate() {
        let Some(gp) = dp else { continue };
        for (q, dq) in dofs.iter().enumerate() {
            let Some(gq) = dq else { continue };
            k[(*gp, *gq)] += element[p][q];
        }
    }
}

/// Static condensation onto the first `kept` degrees of freedom.
fn condense(k: &Mat<f64>, kept: usize) -> Result<Mat<f64>> {
    let total = k.nrows();
    let k_oo = k.submatrix(kept, kept, total - kept, total - kept).to_owned();
    let k_ol = k.submatrix(kept, 0, total - kept, kept).to_owned();
    let k_ll = k.submatrix(0, 0, kept, kept);
    let llt = k_oo
        .llt(Side::Lower)
        .map_err(|_| Error::Numerical("the frame's internal stiffness is singular (is it a mechanism?)".into()))?;
    let x = llt.solve(&k_ol);
    let mut condensed = k_ll.to_owned() - k_ol.transpose() * &x;
    for i in 0..kept {
        for j in 0..i {
            let mean = 0.5 * (condensed[(i, j)] + condensed[(j, i)]);
            condensed[(i, j)] = mean;
            condensed[(j, i)] = mean;
        }
    }
    Ok(condensed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-bay portal with axially rigid members and beam/column flexibility ratio
    /// ρ = (I_b/L)/(I_c/h): the slope-deflection closed form (Chopra, Dynamics of Structures, Eq. 1.3.5
    /// in general form) is k = (24EI_c/h³)·(6ρ + 1)/(6ρ + 4).
    fn portal_stiffness(beam_inertia: f64) -> f64 {
        let column = Section { area: 1e3, inertia: 1e-4 };
        let beam = Section { area: 1e3, inertia: beam_inertia };
        let spec = FrameSpec {
            bay_widths: vec![6.0],
            storey_heights: vec![4.0],
            storeys: vec![StoreySections { beam, exterior_column: column, interior_column: column }],
            youngs_modulus: 2.0e11,
            steel_density: 7850.0,
            dead_load_per_storey_height: 1.0e3,
            gravity: 9.81,
            wind_width: 10.0,
            storeys_per_damper_group: 1,
            damper_bay_width: 6.0,
        };
        spec.build().unwrap().stiffness[(0, 0)]
    }

    #[test]
    fn portal_matches_slope_deflection_closed_form() {
        let (e, ic, h, l): (f64, f64, f64, f64) = (2.0e11, 1e-4, 4.0, 6.0);
        for ib in [1e-8, 1e-4, 3e-4, 1e-1] {
            let rho = (ib / l) / (ic / h);
            let expected = 24.0 * e * ic / h.powi(3) * (6.0 * rho + 1.0) / (6.0 * rho + 4.0);
            let k = portal_stiffness(ib);
            assert!((k / expected - 1.0).abs() < 1e-6, "I_b = {ib}: {k} vs {expected}");
        }
    }
}
