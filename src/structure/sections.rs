//! Cross-section properties of the members of a steel frame.

/// What the frame element needs of a member's section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Area (m²): axial stiffness and self-weight.
    pub area: f64,
    /// Second moment of area about the bending axis (m⁴).
    pub inertia: f64,
}

const INCH: f64 = 0.0254;

impl Section {
    /// An AISC wide-flange shape from its tabulated area (in²) and strong-axis inertia (in⁴).
    pub fn wide_flange(area_in2: f64, inertia_in4: f64) -> Self {
        Section { area: area_in2 * INCH.powi(2), inertia: inertia_in4 * INCH.powi(4) }
    }

    /// A square hollow box of outer side `side` and wall `wall` (m).
    pub fn square_box(side: f64, wall: f64) -> Self {
        let inner = side - 2.0 * wall;
        Section { area: side * side - inner * inner, inertia: (side.powi(4) - inner.powi(4)) / 12.0 }
    }
}

/// AISC Steel Construction Manual properties (A in², Ix in⁴) of the beams of Table 1.
pub mod aisc {
    use super::Section;
    pub fn w36x282() -> Section {
        Section::wide_flange(82.9, 19600.0)
    }
    pub fn w36x194() -> Section {
        Section::wide_flange(57.0, 12100.0)
    }
    pub fn w33x169() -> Section {
        Section::wide_flange(49.5, 9290.0)
    }
    pub fn w27x84() -> Section {
        Section::wide_flange(24.7, 2850.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_section_matches_closed_form() {
        // 56 cm box, 7.6 cm wall: A = 0.56² − 0.408², I = (0.56⁴ − 0.408⁴)/12.
        let s = Section::square_box(0.56, 0.076);
        assert!((s.area - (0.3136 - 0.166464)).abs() < 1e-12);
        assert!((s.inertia - (0.56f64.powi(4) - 0.408f64.powi(4)) / 12.0).abs() < 1e-15);
    }

    #[test]
    fn wide_flange_converts_inches() {
        let s = aisc::w27x84();
        assert!((s.area - 24.7 * 6.4516e-4).abs() < 1e-12);
        assert!((s.inertia - 2850.0 * 4.162314256e-7).abs() < 1e-12);
    }
}
