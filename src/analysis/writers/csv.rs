//! The answers as CSV tables: one row per threshold, criterion floor, swept value or storm, with
//! the columns a spreadsheet or a loss-assessment tool reads. Each writer is pure formatting of its
//! answer; the answers' own types say what every column means.

use crate::analysis::answers::demands::Demands;
use crate::analysis::answers::hazard::HazardCurve;
use crate::analysis::certification::certify::Certification;
use crate::analysis::design::serviceability::Serviceability;
use crate::analysis::design::sweep::Sweep;
use crate::analysis::responses::response::Response;
use crate::analysis::sampling::exceedance::ExceedanceCurve;
use std::fmt::Write;

/// The curve as CSV; a certified one with the metamodel's own probability and the correction.
pub fn exceedance_csv(curve: &ExceedanceCurve, certification: Option<&Certification>, response: &Response) -> String {
    let mut out = format!("threshold_{},probability,lower,upper", response.unit_tag());
    if certification.is_some() {
        out += ",metamodel_probability,mismatch_rate,correction,correction_lower,correction_upper";
    }
    out += "\n";
    for i in 0..curve.thresholds.len() {
        out += &format!("{},{},{},{}", curve.thresholds[i], curve.probabilities[i], curve.lower[i], curve.upper[i]);
        if let Some(c) = certification {
            let row = [c.metamodel_probabilities[i], c.mismatch_rate[i], c.correction[i]];
            out += &format!(",{},{},{},{},{}", row[0], row[1], row[2], c.correction_lower[i], c.correction_upper[i]);
        }
        out += "\n";
    }
    out
}

impl HazardCurve {
    /// The curve as CSV, one row per threshold (empty where a value is undefined); the threshold
    /// column named with the response's unit (`threshold_m`, `threshold_m_s2`, `threshold_n`). A
    /// certified curve adds what its reference storms did.
    pub fn csv(&self, unit_tag: &str) -> String {
        let mut out =
            format!("threshold_{unit_tag},annual_probability,lower,upper,cov,mri_years,beyond_calibrated_range");
        if self.certification.is_some() {
            out +=
                ",metamodel_probability,mismatch_rate,correction,correction_lower,correction_upper,uncorrected_bound";
        }
        out += "\n";
        let blank = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
        for i in 0..self.thresholds.len() {
            out += &format!(
                "{},{},{},{},{},{},{}",
                self.thresholds[i],
                self.annual_probability[i],
                self.lower[i],
                self.upper[i],
                blank(self.cov[i]),
                blank(self.mri_years[i]),
                self.probability_beyond_calibrated_range[i]
            );
            if let Some(c) = &self.certification {
                let p = &c.points;
                let row = [p.metamodel_probabilities[i], p.mismatch_rate[i], p.correction[i], p.correction_lower[i]];
                out += &format!(
                    ",{},{},{},{},{},{}",
                    row[0], row[1], row[2], row[3], p.correction_upper[i], c.uncorrected_bound[i]
                );
            }
            out += "\n";
        }
        out
    }
}

impl Serviceability {
    /// One row per criterion and floor: its T-year level with the band, the limit and the
    /// utilisation, the governing floor marked, the criterion's verdict on every row.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "criterion,response,statistic,unit,return_period_years,floor,value,lower,upper,limit,utilisation,governing,verdict\n",
        );
        let blank = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
        for c in &self.criteria {
            let p = &c.profile;
            for i in 0..p.floors.len() {
                let row = [
                    c.name.replace(',', ";"),
                    c.response.name().to_string(),
                    format!("{:?}", c.statistic).to_lowercase(),
                    c.unit.clone(),
                    c.return_period_years.to_string(),
                    p.floors[i].to_string(),
                    blank(p.values[i]),
                    blank(p.lower[i]),
                    blank(p.upper[i]),
                    p.limits[i].to_string(),
                    blank(p.values[i].map(|v| v / p.limits[i])),
                    (p.floors[i] == c.governing_floor).to_string(),
                    format!("{:?}", c.verdict).to_lowercase(),
                ];
                out += &row.join(",");
                out.push('\n');
            }
        }
        out
    }
}

impl Sweep {
    /// One row per value.
    pub fn csv(&self, unit_tag: &str) -> String {
        let blank = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
        let mut out = format!("{},level_{unit_tag},lower,upper\n", self.input);
        for p in &self.results {
            out += &format!("{},{},{},{}\n", p.input_value, blank(p.level), blank(p.lower), blank(p.upper));
        }
        out
    }
}

impl Demands {
    /// pelicun's demand sample: a header of `event-type-location-direction` names (`1-PFA-j-1`,
    /// `1-PID-j-1`), a `Units` row, then one row per storm under its index.
    pub fn pelicun_csv(&self) -> String {
        let floors = self.drift_ratios.first().map_or(0, Vec::len);
        let mut csv = String::new();
        let pfa = (0..=floors).map(|j| format!(",1-PFA-{j}-1"));
        let pid = (1..=floors).map(|j| format!(",1-PID-{j}-1"));
        csv.extend(pfa.chain(pid));
        csv.push_str("\nUnits");
        csv.push_str(&",g".repeat(floors + 1));
        csv.push_str(&",rad".repeat(floors));
        csv.push('\n');
        for (storm, (accelerations, ratios)) in self.floor_accelerations.iter().zip(&self.drift_ratios).enumerate() {
            write!(csv, "{storm}").expect("writing to a string");
            for value in accelerations.iter().chain(ratios) {
                write!(csv, ",{value:e}").expect("writing to a string");
            }
            csv.push('\n');
        }
        csv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two storms of a two-storey building, by hand.
    #[test]
    fn the_csv_is_pelicuns_demand_sample() {
        let demands = Demands {
            wind_speed: 40.0,
            floor_accelerations: vec![vec![0.0, 0.01, 0.02], vec![0.0, 0.03, 0.04]],
            drift_ratios: vec![vec![0.001, 0.002], vec![0.003, 0.004]],
        };
        let expected = ",1-PFA-0-1,1-PFA-1-1,1-PFA-2-1,1-PID-1-1,1-PID-2-1\nUnits,g,g,g,rad,rad\n\
                        0,0e0,1e-2,2e-2,1e-3,2e-3\n1,0e0,3e-2,4e-2,3e-3,4e-3\n";
        assert_eq!(demands.pelicun_csv(), expected);
    }
}
