//! NARX identification from input/output records: one-step-ahead regressors for LARS, the
//! structure selection, and least squares on a structure (directly or from a compressed
//! dictionary). The refinement on the simulation error (Eq. 11) is in `refine`.

use super::damper_law::DamperLaw;
use super::lars::lars_path;
use super::narx::{Exogenous, NarxTerm, free_run, regressors, relative_error, rest_output};
use crate::error::{Error, Result};
use crate::progress::{Observer, check};
use faer::prelude::SolveLstsq;
use faer::{Mat, MatRef};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::sync::Arc;

/// One experiment of one mode, scaled: output, input and the input's mean (the rest load), and for
/// coupling terms every mode's output (shared, not copied).
#[derive(Debug, Clone)]
pub struct Record {
    /// The output: the modal displacement about its value at rest, over the output scale.
    pub y: Arc<[f64]>,
    /// The input: the modal force about its mean, over the input scale.
    pub q: Arc<[f64]>,
    /// The input at rest, before t = 0.
    pub q_rest: f64,
    /// Every retained mode's output by mode index (the own one included); empty without coupling.
    pub outputs: Vec<Arc<[f64]>>,
    /// The mode the record is of.
    pub mode: usize,
    /// The law of velocity terms, where the dampers have one.
    pub law: Option<Arc<DamperLaw>>,
    /// With a law and coupling: per mode, the law's secant at the first difference of its output
    /// ending at each step ([`Record::secants_of`]); otherwise empty.
    pub secants: Vec<Arc<[f64]>>,
}

impl Record {
    /// A record of a mode on its own.
    pub fn single(y: Vec<f64>, q: Vec<f64>, q_rest: f64) -> Record {
        Record { y: y.into(), q: q.into(), q_rest, outputs: Vec::new(), mode: 0, law: None, secants: Vec::new() }
    }

    /// Per mode, S at the first difference of `outputs[j]` ending at each step (at rest at step 0).
    pub fn secants_of(outputs: &[Arc<[f64]>], law: &DamperLaw) -> Vec<Arc<[f64]>> {
        outputs
            .iter()
            .enumerate()
            .map(|(j, y)| {
                std::iter::once(law.secant(j, 0.0)).chain(y.windows(2).map(|w| law.secant(j, w[1] - w[0]))).collect()
            })
            .collect()
    }

    pub(super) fn secant_slices(&self) -> Vec<&[f64]> {
        self.secants.iter().map(|o| &o[..]).collect()
    }

    /// The measured rests of the other modes: the reference starts at rest.
    pub(super) fn output_rests(&self) -> Vec<f64> {
        self.outputs.iter().map(|o| o[0]).collect()
    }

    pub(super) fn output_slices(&self) -> Vec<&[f64]> {
        self.outputs.iter().map(|o| &o[..]).collect()
    }
}

/// Borrows a record's series as the exogenous part of a model.
macro_rules! exogenous {
    ($record:expr, $slices:ident, $rests:ident, $secants:ident) => {{
        Exogenous {
            q: &$record.q,
            q_rest: $record.q_rest,
            outputs: &$slices,
            output_rests: &$rests,
            law: $record.law.as_deref(),
            secants: &$secants,
            mode: $record.mode,
        }
    }};
}

/// Gram matrix and correlations of the one-step-ahead regression y(t) ~ g(z(t)) over t ≥ 1 for the
/// non-constant `terms`, each column centred and scaled to unit norm, as LARS wants them.
pub fn one_step_gram(terms: &[NarxTerm], record: &Record) -> (Vec<f64>, Vec<f64>) {
    let p = terms.len();
    let n = record.y.len();
    let (slices, rests) = (record.output_slices(), record.output_rests());
    let secants = record.secant_slices();
    let ex = exogenous!(record, slices, rests, secants);
    let mut row = vec![0.0; p];
    let (mut sum, mut cross, mut sum_y, mut xy, mut count) = (vec![0.0; p], vec![0.0; p * p], 0.0, vec![0.0; p], 0.0);
    for t in 1..n {
        regressors(terms, &record.y, record.y[0], &ex, t, &mut row);
        let y = record.y[t];
        for i in 0..p {
            sum[i] += row[i];
            xy[i] += row[i] * y;
            for j in 0..=i {
                cross[i * p + j] += row[i] * row[j];
            }
        }
        sum_y += y;
        count += 1.0;
    }
    let mean: Vec<f64> = sum.iter().map(|s| s / count).collect();
    let mean_y = sum_y / count;
    let norm: Vec<f64> =
        (0..p).map(|i| (cross[i * p + i] - count * mean[i] * mean[i]).max(0.0).sqrt().max(f64::MIN_POSITIVE)).collect();
    let mut gram = vec![0.0; p * p];
    for i in 0..p {
        for j in 0..=i {
            let v = (cross[i * p + j] - count * mean[i] * mean[j]) / (norm[i] * norm[j]);
            gram[i * p + j] = v;
            gram[j * p + i] = v;
        }
    }
    let xty = (0..p).map(|i| (xy[i] - count * mean[i] * mean_y) / norm[i]).collect();
    (gram, xty)
}

/// The one-step-ahead design matrix of `terms` on a record, with the next outputs as a last column.
fn design_with_target(terms: &[NarxTerm], record: &Record) -> Result<Mat<f64>> {
    let n = record.y.len();
    let p = terms.len();
    if n <= p + 1 {
        return Err(Error::invalid("duration_s", "the storm is too short for the NARX model"));
    }
    let (slices, rests) = (record.output_slices(), record.output_rests());
    let secants = record.secant_slices();
    let ex = exogenous!(record, slices, rests, secants);
    let mut x = Mat::<f64>::zeros(n - 1, p + 1);
    let mut row = vec![0.0; p];
    for t in 1..n {
        regressors(terms, &record.y, record.y[0], &ex, t, &mut row);
        for (j, v) in row.iter().enumerate() {
            x[(t - 1, j)] = *v;
        }
        x[(t - 1, p)] = record.y[t];
    }
    Ok(x)
}

/// Least squares min ‖X θ − y‖ by QR (for the nearly collinear lagged outputs), from the design
/// matrix with the target as its last column.
fn solve_design(design: MatRef<'_, f64>) -> Result<Vec<f64>> {
    let p = design.ncols() - 1;
    let solution = design.subcols(0, p).qr().solve_lstsq(design.subcols(p, 1));
    let theta: Vec<f64> = (0..p).map(|j| solution[(j, 0)]).collect();
    if theta.iter().all(|v| v.is_finite()) {
        Ok(theta)
    } else {
        Err(Error::Numerical("the one-step least-squares fit failed".into()))
    }
}

/// One-step-ahead least squares of `terms` on a record.
pub fn least_squares(terms: &[NarxTerm], record: &Record) -> Result<Vec<f64>> {
    solve_design(design_with_target(terms, record)?.as_ref())
}

/// A record's one-step regression over a whole dictionary, compressed to the triangular factor R of
/// the QR of [X | y]. Since X = Q R₁ and y = Q z + r with r orthogonal to every column, the least
/// squares of any subset S of the dictionary is the small problem min ‖R_S θ − z‖ on the columns S
/// of R: the same solution as on the whole record, at O(p³) per candidate instead of O(n p²).
pub struct CompressedRegression {
    terms: Vec<NarxTerm>,
    r: Mat<f64>,
}

impl CompressedRegression {
    /// Compresses the one-step regression of `record` on every term of `dictionary`.
    pub fn new(dictionary: &[NarxTerm], record: &Record) -> Result<CompressedRegression> {
        let design = design_with_target(dictionary, record)?;
        let r = design.qr().thin_R().to_owned();
        Ok(CompressedRegression { terms: dictionary.to_vec(), r })
    }

    /// One-step least squares of a subset of the dictionary's terms, in the order given.
    pub fn least_squares(&self, terms: &[NarxTerm]) -> Result<Vec<f64>> {
        let p = self.terms.len();
        let mut small = Mat::<f64>::zeros(p, terms.len() + 1);
        for (j, term) in terms.iter().enumerate() {
            let column = self
                .terms
                .iter()
                .position(|t| t == term)
                .ok_or_else(|| Error::Numerical(format!("the term {term} is not in the compressed dictionary")))?;
            small.col_mut(j).copy_from(self.r.col(column).subrows(0, p));
        }
        small.col_mut(terms.len()).copy_from(self.r.col(p).subrows(0, p));
        solve_design(small.as_ref())
    }
}

/// Free run of a model on a record from the model's own rest state; its output series.
pub fn simulate(terms: &[NarxTerm], theta: &[f64], record: &Record) -> Result<Vec<f64>> {
    let (slices, rests) = (record.output_slices(), record.output_rests());
    let rest = rest_output(terms, theta, record.q_rest, &rests, record.y[0])?;
    let mut out = vec![0.0; record.q.len()];
    let secants = record.secant_slices();
    free_run(terms, theta, &exogenous!(record, slices, rests, secants), rest, &mut out)?;
    Ok(out)
}

/// Simulation (free-run) relative error of a model on a record; +∞ when it diverges.
pub fn simulation_error(terms: &[NarxTerm], theta: &[f64], record: &Record) -> f64 {
    simulate(terms, theta, record).map_or(f64::INFINITY, |y_hat| relative_error(&record.y, &y_hat))
}

/// The structure chosen for one mode, and how it was chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct StructureChoice {
    /// The chosen terms.
    pub terms: Vec<NarxTerm>,
    /// Mean free-run relative error of the one-step fits of the chosen structure.
    pub error: f64,
    /// Distinct candidate structures evaluated.
    pub candidates: usize,
}

/// Candidates within this factor of the best free-run error count as equally good; the one with
/// fewest terms among them wins, since every term costs a polynomial chaos expansion.
const PARSIMONY_FACTOR: f64 = 1.1;

/// Structure selection after Mai et al.: LARS on the one-step-ahead regressors of every record gives
/// a path of growing active sets; every prefix (with the constant) is a candidate; each candidate is
/// fitted by one-step least squares on the `evaluation` records and scored by its mean free-run
/// error; a candidate that diverges on any of them is rejected. The smallest candidate within
/// `PARSIMONY_FACTOR` of the best is then pruned by backward elimination. The dictionary's damper
/// terms then enter one at a time, each the one that lowers the free-run error most, while that
/// lowers it by more than the same factor: they do not go through LARS, whose one-step fit takes
/// the law of the velocity for the second lag it nearly is and builds paths whose free runs diverge.
pub fn select_structure(
    dictionary: &[NarxTerm],
    records: &[Record],
    evaluation: &[Record],
    max_terms: usize,
    observer: &dyn Observer,
) -> Result<StructureChoice> {
    let non_constant: Vec<NarxTerm> =
        dictionary.iter().copied().filter(|t| !t.is_constant() && t.damper.is_none()).collect();
    let has_constant = dictionary.iter().any(NarxTerm::is_constant);
    let paths: Vec<Vec<Vec<NarxTerm>>> = records
        .par_iter()
        .map(|record| {
            let (gram, xty) = one_step_gram(&non_constant, record);
            let steps = lars_path(&gram, &xty, max_terms.saturating_sub(has_constant as usize));
            steps
                .iter()
                .map(|step| {
                    let mut set: Vec<NarxTerm> = step.active.iter().map(|&i| non_constant[i]).collect();
                    if has_constant {
                        set.push(NarxTerm::CONSTANT);
                    }
                    set.sort();
                    set
                })
                .collect()
        })
        .collect();
    let candidates: BTreeSet<Vec<NarxTerm>> = paths.into_iter().flatten().collect();
    let compressed: Vec<CompressedRegression> =
        evaluation.par_iter().map(|r| CompressedRegression::new(dictionary, r)).collect::<Result<_>>()?;
    // Each candidate costs a free run of every evaluation record; once a stop is requested the
    // remaining ones are skipped (scored infinite) and the stop is reported below.
    let mean_error = |terms: &[NarxTerm]| -> f64 {
        if observer.cancelled() {
            return f64::INFINITY;
        }
        let total: f64 = evaluation
            .iter()
            .zip(&compressed)
            .map(|(r, c)| c.least_squares(terms).map_or(f64::INFINITY, |theta| simulation_error(terms, &theta, r)))
            .sum();
        total / evaluation.len() as f64
    };
    let scored: Vec<(f64, Vec<NarxTerm>)> =
        candidates.par_iter().map(|terms| (mean_error(terms), terms.clone())).filter(|(e, _)| e.is_finite()).collect();
    check(observer)?;
    let best = scored.iter().map(|(e, _)| *e).fold(f64::INFINITY, f64::min);
    let tolerance = best * PARSIMONY_FACTOR + 1e-15;
    let (mut error, mut terms) = scored
        .iter()
        .filter(|(e, _)| *e <= tolerance)
        .min_by(|a, b| a.1.len().cmp(&b.1.len()).then(a.0.total_cmp(&b.0)))
        .cloned()
        .ok_or_else(|| Error::Numerical("every candidate NARX structure diverged in free run".into()))?;
    // Backward elimination: LARS prefixes need not contain the smallest adequate set (correlated
    // input lags enter early), so drop terms while the error stays within the same tolerance.
    loop {
        let removal = (0..terms.len())
            .into_par_iter()
            .filter(|&i| !terms[i].is_constant())
            .map(|i| {
                let mut fewer = terms.clone();
                fewer.remove(i);
                (mean_error(&fewer), fewer)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match removal {
            Some((e, fewer)) if e <= tolerance && fewer.len() > 1 => {
                error = e;
                terms = fewer;
            }
            _ => break,
        }
    }
    let mut candidates = candidates.len();
    let mut damper_terms: Vec<NarxTerm> = dictionary.iter().copied().filter(|t| t.damper.is_some()).collect();
    while !damper_terms.is_empty() {
        let addition = damper_terms
            .par_iter()
            .map(|term| {
                let mut more = terms.clone();
                more.push(*term);
                more.sort();
                (mean_error(&more), *term, more)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        candidates += damper_terms.len();
        match addition {
            Some((e, term, more)) if e * PARSIMONY_FACTOR < error => {
                error = e;
                terms = more;
                damper_terms.retain(|t| *t != term);
            }
            _ => break,
        }
    }
    check(observer)?;
    Ok(StructureChoice { terms, error, candidates })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::surrogate::narx::NarxOptions;
    use crate::uncertainty::rng_from_seed;
    use rand::RngExt;

    pub(in crate::surrogate) fn arx() -> (Vec<NarxTerm>, Vec<f64>) {
        let terms =
            vec![NarxTerm::CONSTANT, NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, None)];
        (terms, vec![0.002, 0.05, 1.6, -0.7])
    }

    /// Data from a known ARX(2) (exact, no noise) with a smooth random input.
    pub(in crate::surrogate) fn record(theta: &[f64], terms: &[NarxTerm], seed: u64) -> Record {
        let mut rng = rng_from_seed(seed);
        let mut q = vec![0.0; 4000];
        let mut state = 0.0;
        for v in q.iter_mut() {
            state = 0.95 * state + rng.random::<f64>() - 0.5;
            *v = 1.0 + state;
        }
        let r = Record::single(vec![0.0; 4000], q, 1.0);
        let y = simulate(terms, theta, &r).unwrap();
        Record { y: y.into(), ..r }
    }

    /// Structure selection over the paper's 10-term dictionary finds the true ARX terms, and least
    /// squares on them recovers the coefficients.
    #[test]
    fn identification_recovers_a_known_arx_model() {
        let (terms, theta) = arx();
        let records: Vec<Record> = (1..=3).map(|seed| record(&theta, &terms, seed)).collect();
        let choice =
            select_structure(&NarxOptions::default().dictionary(0, 1, false), &records, &records, 8, &Silent).unwrap();
        let mut truth = terms.clone();
        truth.sort();
        assert_eq!(choice.terms, truth);
        assert!(choice.candidates >= 3);
        let fitted = least_squares(&choice.terms, &records[0]).unwrap();
        let expected: Vec<f64> =
            choice.terms.iter().map(|t| theta[terms.iter().position(|u| u == t).unwrap()]).collect();
        for (a, b) in fitted.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-9, "{fitted:?}");
        }
        assert!(simulation_error(&choice.terms, &fitted, &records[0]) < 1e-15);
    }

    /// A damper's law in the data is found: it enters after the polynomial structure, on the
    /// free-run error, and the fit on the chosen terms reproduces the data.
    #[test]
    fn identification_finds_the_law_of_the_velocity() {
        use crate::surrogate::DamperLaw;
        use crate::surrogate::narx::DamperTerm;
        let law = Arc::new(DamperLaw { exponent: 0.38, knees: vec![1e-3] });
        let (mut terms, mut theta) = arx();
        terms.push(NarxTerm::damper(DamperTerm::Law, 1, None));
        theta.push(-0.004);
        let records: Vec<Record> = (1..=3)
            .map(|seed| {
                let mut r = Record { law: Some(law.clone()), ..record(&[0.0; 4], &arx().0, seed) };
                r.y = simulate(&terms, &theta, &r).unwrap().into();
                r
            })
            .collect();
        let dictionary = NarxOptions { damper_terms: true, ..Default::default() }.dictionary(0, 1, true);
        assert_eq!(dictionary.iter().filter(|t| t.damper.is_some()).count(), 1);
        let choice = select_structure(&dictionary, &records, &records, 8, &Silent).unwrap();
        assert!(choice.terms.contains(&NarxTerm::damper(DamperTerm::Law, 1, None)), "{:?}", choice.terms);
        let fitted = least_squares(&choice.terms, &records[0]).unwrap();
        assert!(simulation_error(&choice.terms, &fitted, &records[0]) < 1e-12);
    }

    /// The least squares of any subset from the compressed dictionary equal those on the record.
    #[test]
    fn compressed_least_squares_equal_the_direct_fit() {
        let (terms, theta) = arx();
        let data = record(&theta, &terms, 3);
        let dictionary = NarxOptions::default().dictionary(0, 1, false);
        let compressed = CompressedRegression::new(&dictionary, &data).unwrap();
        for subset in [&dictionary[..], &dictionary[..4], &dictionary[3..], &[dictionary[5], dictionary[1]]] {
            let direct = least_squares(subset, &data).unwrap();
            let small = compressed.least_squares(subset).unwrap();
            let scale = direct.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (a, b) in direct.iter().zip(&small) {
                assert!((a - b).abs() <= 1e-9 * scale, "{subset:?}: {direct:?} vs {small:?}");
            }
        }
        assert!(compressed.least_squares(&[NarxTerm::output(7, 1, Some(2))]).is_err());
    }
}
