use super::*;
use crate::structure::{Modes, frame40};

fn ground_damper() -> crate::structure::DamperPlacement {
    crate::structure::DamperPlacement { lower_floor: None, upper_floor: 0, cos_angle: 1.0, group: 0 }
}

fn relative(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Residual and M-orthogonality of the computed modes: each pair satisfies K φ = ω² M φ to
/// rounding, whatever the eigen-solver.
fn check_eigenpairs(structure: &SpatialStructure, modes: &SpatialModes) {
    let (k, m) = (&structure.stiffness, &structure.mass);
    for a in 0..modes.count() {
        let phi = modes.shapes.col(a);
        let kphi = k * phi;
        let mphi = m * phi;
        let lambda = modes.frequencies[a].powi(2);
        let residual: f64 = (0..structure.dofs()).map(|i| (kphi[i] - lambda * mphi[i]).powi(2)).sum::<f64>().sqrt();
        let scale: f64 = (0..structure.dofs()).map(|i| kphi[i].powi(2)).sum::<f64>().sqrt();
        assert!(residual < 1e-9 * scale, "mode {}: residual {residual} of {scale}", a + 1);
        for b in 0..a {
            let cross = modes.shapes.col(b).transpose() * &mphi;
            assert!(
                cross.abs() < 1e-9 * modes.modal_masses[a],
                "modes {} and {} not M-orthogonal: {cross}",
                b + 1,
                a + 1
            );
        }
    }
}

/// The symmetric building separates into the plane frame's problem: K = K₂ ⊗ diag(2, 2, B²/2) and
/// M = m ⊗ diag(2, 2, 2r²) with r² = B²/6, so every plane mode ω_k appears twice in sway and once
/// as a twist at √(B²/2 / (2 B²/6)) ω_k = √3 ω_k, the twist's shape the plane mode's.
#[test]
fn the_symmetric_building_sways_as_the_plane_frame_and_twists_at_root_three() {
    let building = frame40_3d([0.0, 0.0]).unwrap();
    assert_eq!(
        (building.floors(), building.dofs(), building.dampers.len(), building.damper_groups()),
        (40, 120, 160, 4)
    );
    let plane = Modes::all(&frame40().unwrap()).unwrap();
    let mut expected: Vec<f64> = plane.frequencies.iter().flat_map(|&w| [w, w, 3f64.sqrt() * w]).collect();
    expected.sort_by(f64::total_cmp);
    let modes = SpatialModes::of(&building, 12).unwrap();
    for (m, (w, e)) in modes.frequencies.iter().zip(&expected).enumerate() {
        assert!(relative(*w, *e) < 1e-9, "mode {}: ω = {w}, expected {e}", m + 1);
    }
    check_eigenpairs(&building, &modes);
    // The first two are the first plane mode in sway, turned to x and to y (they share ω), the
    // third its twist: every floor's components in proportion to the plane shape.
    for m in 0..3 {
        let expected = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]][m];
        for (share, e) in modes.shares[m].iter().zip(expected) {
            assert!((share - e).abs() < 1e-9, "mode {}: shares {:?}", m + 1, modes.shares[m]);
        }
        for d in [Dof::X, Dof::Y, Dof::Rotation] {
            let roof = modes.at(m, 39, d);
            if roof.abs() < 1e-6 {
                continue;
            }
            for floor in 0..40 {
                let ratio = modes.at(m, floor, d) / roof;
                assert!(
                    (ratio - plane.shapes[(floor, 0)]).abs() < 1e-8,
                    "mode {} {d:?} floor {}: {ratio}",
                    m + 1,
                    floor + 1
                );
            }
        }
    }
    // The twist mode is scaled so that the roof turns by 1/r: a point at r moves by 1.
    let radius = FRAME40_3D_PLAN.radius_of_gyration();
    assert!((modes.at(2, 39, Dof::Rotation).abs() * radius - 1.0).abs() < 1e-12);
}

/// With the centre of mass moved by e along y, x-sway and twist couple and y-sway stays apart. The
/// problem still separates over the plane modes: for plane mode k (K₂φ = λ_k m φ), the building's
/// modes are (aφ, 0, bφ) with λ_k [[2, 2e], [2e, κ]] (a, b) = ω² [[2, 0], [0, 2r²]] (a, b), κ the
/// frames' Σ lever², two roots of a quadratic per plane mode, in closed form.
#[test]
fn an_eccentric_building_couples_sway_and_twist_as_the_closed_form_says() {
    let e = 2.44;
    let building = frame40_3d([0.0, e]).unwrap();
    let plane = Modes::all(&frame40().unwrap()).unwrap();
    let half = 12.2;
    let kappa = (half - e).powi(2) + (half + e).powi(2) + 2.0 * half * half;
    let r2 = FRAME40_3D_PLAN.radius_of_gyration().powi(2);
    // det([[2, 2e], [2e, κ]] − μ diag(2, 2r²)) = 0: 4r² μ² − (2κ + 4r²) μ + (2κ − 4e²) = 0.
    let (qa, qb, qc) = (4.0 * r2, -(2.0 * kappa + 4.0 * r2), 2.0 * kappa - 4.0 * e * e);
    let root = (qb * qb - 4.0 * qa * qc).sqrt();
    let mu = [(-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)];
    // Twist share of the coupled mode at μ: (a, b) ∝ (2e, 2μ − 2)... from the first row,
    // 2a + 2eb = 2μa, so b/a = (μ − 1)/e and the twist share is r²b²/(a² + r²b²).
    let twist_share = |mu: f64| {
        let ratio = (mu - 1.0) / e;
        r2 * ratio * ratio / (1.0 + r2 * ratio * ratio)
    };
    let mut expected: Vec<(f64, f64)> = plane
        .frequencies
        .iter()
        .flat_map(|&w| [(w, 0.0), (w * mu[0].sqrt(), twist_share(mu[0])), (w * mu[1].sqrt(), twist_share(mu[1]))])
        .collect();
    expected.sort_by(|a, b| a.0.total_cmp(&b.0));
    let modes = SpatialModes::of(&building, 9).unwrap();
    check_eigenpairs(&building, &modes);
    for (m, (w, (e_w, e_twist))) in modes.frequencies.iter().zip(&expected).enumerate() {
        assert!(relative(*w, *e_w) < 1e-9, "mode {}: ω = {w}, expected {e_w}", m + 1);
        assert!(
            (modes.shares[m][2] - e_twist).abs() < 1e-9,
            "mode {}: shares {:?}, twist {e_twist}",
            m + 1,
            modes.shares[m]
        );
        let sum: f64 = modes.shares[m].iter().sum();
        assert!((sum - 1.0).abs() < 1e-12);
    }
}

/// One storey described by its properties, centre of mass at e along x: x-sway alone at √(k_x/m),
/// y-sway and twist coupled through K = [[k_y, −e k_y], [−e k_y, k_θ + e² k_y]], M = diag(m, I).
#[test]
fn a_storey_of_given_properties_has_the_closed_form_frequencies() {
    let (m, inertia, kx, ky, kt, e) = (2.0e5, 8.0e6, 3.0e7, 5.0e7, 9.0e9, 1.5);
    let storey = StoreyProperties {
        elevation: 4.0,
        plan: FloorPlan { breadth: 20.0, depth: 12.0 },
        mass: m,
        moment_of_inertia: Some(inertia),
        centre_of_mass: [e, 0.0],
        stiffness_x: kx,
        stiffness_y: ky,
        torsional_stiffness: kt,
    };
    let building = from_storeys(std::slice::from_ref(&storey), 1.0, vec![]).unwrap();
    let modes = SpatialModes::of(&building, 3).unwrap();
    // det(K − ω² M) = 0 for the y-θ pair: m I ω⁴ − (m (k_θ + e² k_y) + I k_y) ω² + k_y k_θ = 0.
    let (a, b, c) = (m * inertia, -(m * (kt + e * e * ky) + inertia * ky), ky * kt);
    let root = (b * b - 4.0 * a * c).sqrt();
    let mut expected = [(kx / m).sqrt(), ((-b - root) / (2.0 * a)).sqrt(), ((-b + root) / (2.0 * a)).sqrt()];
    expected.sort_by(f64::total_cmp);
    for (w, e) in modes.frequencies.iter().zip(expected) {
        assert!(relative(*w, e) < 1e-12, "ω = {w}, expected {e}");
    }
    // Without a moment of inertia the floor is an even plate: I = m (B² + D²)/12.
    let plate = from_storeys(
        &[StoreyProperties { moment_of_inertia: None, centre_of_mass: [0.0, 0.0], ..storey }],
        1.0,
        vec![],
    )
    .unwrap();
    assert!(relative(plate.mass[(2, 2)], m * (400.0 + 144.0) / 12.0) < 1e-15);
    let twist = SpatialModes::of(&plate, 3).unwrap().frequencies[2];
    assert!(relative(twist, (kt / plate.mass[(2, 2)]).sqrt()) < 1e-12, "twist at {twist}");
}

#[test]
fn a_damper_sees_its_point_move_along_its_direction() {
    let damper = PlanDamper { placement: ground_damper(), direction: plan_direction(90.0), position: [12.2, 3.0] };
    // Along y at x = 12.2 − 1 from a centre of mass at (1, 0): (0, 1, 11.2).
    let w = damper.weights([1.0, 0.0]);
    assert_eq!(w, [0.0, 1.0, 11.2]);
    let along_x = PlanDamper { direction: plan_direction(0.0), ..damper };
    // Along x at y = 3 from the centre of mass: u_x − 3θ.
    assert_eq!(along_x.weights([1.0, 0.0]), [1.0, 0.0, -3.0]);
}

#[test]
fn bad_buildings_are_refused_by_field() {
    let storey = |centre: [f64; 2]| StoreyProperties {
        elevation: 4.0,
        plan: FloorPlan { breadth: 20.0, depth: 12.0 },
        mass: 1.0e5,
        moment_of_inertia: None,
        centre_of_mass: centre,
        stiffness_x: 1.0e7,
        stiffness_y: 1.0e7,
        torsional_stiffness: 1.0e9,
    };
    let field = |result: Result<SpatialStructure>| match result {
        Err(Error::Invalid { field, .. }) => field,
        other => panic!("expected a refusal, got {other:?}"),
    };
    assert_eq!(field(from_storeys(&[storey([11.0, 0.0])], 1.0, vec![])), "centres_of_mass[0]");
    assert_eq!(field(from_storeys(&[storey([0.0, f64::NAN])], 1.0, vec![])), "storeys[0].centre_of_mass[1]");
    assert_eq!(
        field(from_storeys(&[StoreyProperties { torsional_stiffness: -1.0, ..storey([0.0, 0.0]) }], 1.0, vec![])),
        "storeys[0].torsional_stiffness_n_m_per_rad"
    );
    let outside = PlanDamper { placement: ground_damper(), direction: [1.0, 0.0], position: [0.0, 7.0] };
    assert_eq!(field(from_storeys(&[storey([0.0, 0.0])], 1.0, vec![outside])), "dampers[0].position");
    assert_eq!(field(frame40_3d([0.0, 7.0])), "eccentricity_m");
    let small = frame40_3d([0.0, 0.0]).unwrap();
    let wrong = Mat::<f64>::identity(6, 6);
    assert_eq!(
        field(SpatialStructure::new(
            wrong.clone(),
            wrong,
            vec![3.0],
            vec![FRAME40_3D_PLAN],
            vec![[0.0, 0.0]],
            1.0,
            vec![]
        )),
        "stiffness"
    );
    assert_eq!(small.corners(0)[0], [12.2, 12.2]);
}
