//! SVG figures: exceedance curves with their bands (the paper's Fig. 7), a certified one beside
//! the metamodel's own, the scatter of peaks, reference against metamodel (Fig. 6), annual curves
//! with return levels, fragility curves, peak profiles, serviceability checks and sweeps.

use crate::analysis::answers::fragility::Fragility;
use crate::analysis::answers::hazard::HazardCurve;
use crate::analysis::answers::profile::PeakProfile;
use crate::analysis::certification::certify::Certification;
use crate::analysis::design::serviceability::Serviceability;
use crate::analysis::design::sweep::{Sweep, SweepPoint};
use crate::analysis::sampling::exceedance::ExceedanceCurve;
use plotters::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

/// Largest magnitude an axis spans; plotters' tick search does not end on an infinite or
/// overflowing range, so values beyond are clipped to it (no response of a building comes near).
const AXIS_LIMIT: f64 = 1e12;

/// A finite axis range covering `values` (clipped to ±[`AXIS_LIMIT`]) with a margin of `pad` of
/// the span on each side; non-finite values are ignored and a degenerate range is widened.
fn axis_range(values: impl Iterator<Item = f64>, pad: f64) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|x| x.is_finite())
        .map(|x| x.clamp(-AXIS_LIMIT, AXIS_LIMIT))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if lo > hi {
        return 0.0..1.0;
    }
    let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
    lo - pad * span..hi + pad * span
}

const COLOURS: [RGBColor; 3] = [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44)];

fn draw_curves(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    curves: &[(&str, &ExceedanceCurve)],
    x_label: &str,
) {
    let range = axis_range(curves.iter().flat_map(|(_, c)| c.thresholds.iter().copied()), 0.02);
    let Ok(mut chart) = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(range, 0.0..1.0)
    else {
        return;
    };
    let _ = chart.configure_mesh().x_desc(x_label).y_desc("P(peak > x)").draw();
    for (i, (label, curve)) in curves.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let band: Vec<(f64, f64)> = curve
            .thresholds
            .iter()
            .zip(&curve.upper)
            .map(|(x, y)| (*x, *y))
            .chain(curve.thresholds.iter().zip(&curve.lower).rev().map(|(x, y)| (*x, *y)))
            .collect();
        let _ = chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15).filled())));
        let line: Vec<(f64, f64)> = curve.thresholds.iter().zip(&curve.probabilities).map(|(x, p)| (*x, *p)).collect();
        if let Ok(series) = chart.draw_series(LineSeries::new(line, colour.stroke_width(2))) {
            series
                .label(label.to_string())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
        }
    }
    let _ = chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw();
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

type FloorChart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// Values (x, from 0 where `range` starts below) against the floors up to `top` (y), the mesh drawn.
fn floor_chart<'a, 'b>(
    root: &'a Area<'b>,
    range: std::ops::Range<f64>,
    top: f64,
    x_label: &str,
) -> Option<FloorChart<'a, 'b>> {
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(48)
        .build_cartesian_2d(range.start.max(0.0)..range.end, 0.0..top + 1.0)
        .ok()?;
    let _ = chart.configure_mesh().x_desc(x_label).y_desc("floor").draw();
    Some(chart)
}

/// A serviceability check's profiles against their limits: at every judged floor, the T-year level
/// over its limit (the utilisation) with its band, one colour per criterion, and the limit at 1.
pub fn serviceability_svg(check: &Serviceability) -> String {
    let ratios = |values: &[Option<f64>], limits: &[f64]| -> Vec<Option<f64>> {
        values.iter().zip(limits).map(|(v, limit)| v.map(|v| v / limit)).collect()
    };
    let drawn: Vec<_> = check
        .criteria
        .iter()
        .map(|c| {
            let p = &c.profile;
            let floors: Vec<f64> = p.floors.iter().map(|&f| f as f64).collect();
            (
                c.name.clone(),
                floors,
                ratios(&p.values, &p.limits),
                ratios(&p.lower, &p.limits),
                ratios(&p.upper, &p.limits),
            )
        })
        .collect();
    let top = check.criteria.iter().flat_map(|c| c.profile.floors.iter().copied()).max().unwrap_or(1) as f64;
    render((640, 640), |root| {
        let all = drawn.iter().flat_map(|d| d.2.iter().chain(&d.3).chain(&d.4).flatten().copied());
        let Some(mut chart) = floor_chart(root, axis_range(all.chain([0.0, 1.0]), 0.04), top, "T-year level / limit")
        else {
            return;
        };
        let _ = chart.draw_series(LineSeries::new([(1.0, 0.0), (1.0, top + 1.0)], BLACK.stroke_width(1)));
        for (i, (name, floors, values, lower, upper)) in drawn.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points = |xs: &[Option<f64>]| -> Vec<(f64, f64)> {
                xs.iter().zip(floors).filter_map(|(x, f)| Some(((*x)?, *f))).collect()
            };
            let band: Vec<(f64, f64)> = points(lower).into_iter().chain(points(upper).into_iter().rev()).collect();
            let _ = chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15).filled())));
            if let Ok(series) = chart.draw_series(LineSeries::new(points(values), colour.stroke_width(2))) {
                series
                    .label(name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
            }
        }
        let _ = chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw();
    })
}

/// A sweep: the T-year level against the swept input's value, with its band, and a limit when
/// one is given.
pub fn sweep_svg(sweep: &Sweep, y_label: &str, limit: Option<f64>) -> String {
    let at = |pick: fn(&SweepPoint) -> Option<f64>| -> Vec<(f64, f64)> {
        sweep.results.iter().filter_map(|p| Some((p.input_value, pick(p)?))).collect()
    };
    let (values, lower, upper) = (at(|p| p.level), at(|p| p.lower), at(|p| p.upper));
    render((760, 500), |root| {
        let x_range = axis_range(sweep.results.iter().map(|p| p.input_value), 0.04);
        let ys = lower.iter().chain(&upper).map(|p| p.1).chain(limit);
        let y_range = axis_range(ys, 0.06);
        let Ok(mut chart) = ChartBuilder::on(root)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(x_range.clone(), y_range.start.max(0.0)..y_range.end)
        else {
            return;
        };
        let _ = chart.configure_mesh().x_desc(sweep.input.as_str()).y_desc(y_label).draw();
        let band: Vec<(f64, f64)> = lower.iter().copied().chain(upper.iter().rev().copied()).collect();
        let colour = COLOURS[0];
        let _ = chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15).filled())));
        let _ = chart.draw_series(LineSeries::new(values.clone(), colour.stroke_width(2)));
        let _ = chart.draw_series(values.iter().map(|&p| Circle::new(p, 4, colour.filled())));
        if let Some(limit) = limit {
            let line = [(x_range.start, limit), (x_range.end, limit)];
            let _ = chart.draw_series(LineSeries::new(line, COLOURS[1].stroke_width(1)));
        }
    })
}

/// An SVG of `size` pixels on a white ground, drawn by `draw`.
fn render(size: (u32, u32), draw: impl FnOnce(&Area<'_>)) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let _ = root.fill(&WHITE);
        draw(&root);
        let _ = root.present();
    }
    svg
}

/// A peak profile up the height: the quantile at each floor with its band, and the mean peak.
pub fn profile_svg(profile: &PeakProfile, x_label: &str) -> String {
    render((560, 640), |root| {
        let range = axis_range(profile.lower.iter().chain(&profile.upper).chain(&profile.means).copied(), 0.04);
        let top = profile.floors.iter().copied().max().unwrap_or(1) as f64;
        let Some(mut chart) = floor_chart(root, range, top, x_label) else {
            return;
        };
        let at = |values: &[f64]| -> Vec<(f64, f64)> {
            values.iter().zip(&profile.floors).map(|(x, floor)| (*x, *floor as f64)).collect()
        };
        let band: Vec<(f64, f64)> =
            at(&profile.lower).into_iter().chain(at(&profile.upper).into_iter().rev()).collect();
        let colour = COLOURS[0];
        let _ = chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15).filled())));
        let percent = 100.0 * profile.quantile;
        let lines = [
            (format!("{percent} % peak"), colour, at(&profile.values)),
            ("mean peak".to_string(), COLOURS[1], at(&profile.means)),
        ];
        for (label, colour, line) in lines {
            if let Ok(series) = chart.draw_series(LineSeries::new(line, colour.stroke_width(2))) {
                series
                    .label(label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
            }
        }
        let _ = chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw();
    })
}

/// Exceedance curves with their confidence bands.
pub fn exceedance_svg(curves: &[(&str, &ExceedanceCurve)], x_label: &str) -> String {
    render((720, 480), |root| draw_curves(root, curves, x_label))
}

/// The figure of an exceedance curve labelled `label`; a certified one beside the metamodel's own
/// curve with its band, as an uncertified answer would have drawn it.
pub fn exceedance_figure(curve: &ExceedanceCurve, certification: Option<&Certification>, label: &str) -> String {
    let Some(c) = certification else { return exceedance_svg(&[("PC-NARX", curve)], label) };
    let metamodel = ExceedanceCurve {
        probabilities: c.metamodel_probabilities.clone(),
        lower: c.metamodel_lower.clone(),
        upper: c.metamodel_upper.clone(),
        ..curve.clone()
    };
    exceedance_svg(&[("PC-NARX", &metamodel), ("certified", curve)], label)
}

/// Validation figure: peaks scatter (left) and both exceedance curves (right).
pub fn validation_svg(reference: &[f64], metamodel: &[f64], curves: &[(&str, &ExceedanceCurve)]) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1200, 520)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let (left, right) = root.split_horizontally(560);
        let range = axis_range(reference.iter().chain(metamodel).copied(), 0.05);
        let (lo, hi) = (range.start, range.end);
        if let Ok(mut chart) = ChartBuilder::on(&left)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(lo..hi, lo..hi)
        {
            let _ = chart
                .configure_mesh()
                .x_desc("reference peak roof displacement (m)")
                .y_desc("metamodel peak (m)")
                .draw();
            let _ = chart.draw_series(LineSeries::new(vec![(lo, lo), (hi, hi)], BLACK.mix(0.5)));
            let _ = chart.draw_series(
                reference.iter().zip(metamodel).map(|(x, y)| Circle::new((*x, *y), 3, COLOURS[0].filled())),
            );
        }
        draw_curves(&right, curves, "peak roof displacement x (m)");
        let _ = root.present();
    }
    svg
}

/// A curve to draw: its name, probabilities, band and colour.
type DrawnCurve<'a> = (&'a str, &'a [f64], &'a [f64], &'a [f64], RGBColor);

/// The annual exceedance curve with its band on a logarithmic probability axis, the mean
/// recurrence interval 1/P on the right-hand axis, and the return levels marked; a certified one
/// beside the metamodel's own.
pub fn hazard_svg(curve: &HazardCurve, x_label: &str) -> String {
    let positive = |p: f64| p.is_finite() && p > 0.0;
    // A certified curve beside the metamodel's own, as an uncertified answer would have drawn it.
    let mut drawn: Vec<DrawnCurve> = Vec::new();
    if let Some(c) = &curve.certification {
        let p = &c.points;
        drawn.push(("PC-NARX", &p.metamodel_probabilities, &p.metamodel_lower, &p.metamodel_upper, COLOURS[0]));
        drawn.push(("certified", &curve.annual_probability, &curve.lower, &curve.upper, COLOURS[2]));
    } else {
        drawn.push(("PC-NARX", &curve.annual_probability, &curve.lower, &curve.upper, COLOURS[0]));
    }
    let floor = drawn
        .iter()
        .flat_map(|(_, p, lower, _, _)| p.iter().chain(lower.iter()))
        .copied()
        .filter(|p| positive(*p))
        .fold(1.0, f64::min)
        .max(1e-12)
        / 2.0;
    render((760, 500), |root| {
        let x_range = axis_range(curve.thresholds.iter().copied(), 0.02);
        let Ok(mut chart) = ChartBuilder::on(root)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .right_y_label_area_size(64)
            .build_cartesian_2d(x_range.clone(), (floor..1.0).log_scale())
            .map(|chart| chart.set_secondary_coord(x_range, (1.0..1.0 / floor).log_scale()))
        else {
            return;
        };
        let _ = chart.configure_mesh().x_desc(x_label).y_desc("annual P(peak > x)").draw();
        let _ = chart.configure_secondary_axes().y_desc("mean recurrence interval (years)").draw();
        let clip = |p: f64| p.clamp(floor, 1.0);
        let x = &curve.thresholds;
        for &(name, probabilities, lower, upper, colour) in &drawn {
            let band: Vec<(f64, f64)> = x
                .iter()
                .zip(upper)
                .map(|(x, p)| (*x, clip(*p)))
                .chain(x.iter().zip(lower).rev().map(|(x, p)| (*x, clip(*p))))
                .collect();
            let _ = chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15).filled())));
            let line = x.iter().zip(probabilities).filter(|(_, p)| positive(**p)).map(|(x, p)| (*x, *p));
            if let Ok(series) = chart.draw_series(LineSeries::new(line, colour.stroke_width(2))) {
                series
                    .label(name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
            }
        }
        if drawn.len() > 1 {
            let _ = chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw();
        }
        let marks = curve.return_levels.iter().filter_map(|r| Some((r.value?, 1.0 / r.return_period_years)));
        let _ = chart.draw_series(marks.clone().map(|(x, p)| Circle::new((x, p), 4, COLOURS[1].filled())));
        let _ = chart.draw_series(marks.map(|(x, p)| {
            Text::new(format!("{:.0} y", 1.0 / p), (x, p), ("sans-serif", 12).into_font().color(&COLOURS[1]))
        }));
    })
}

/// Fragility curves P(peak > x | v) with their bands, and the fitted lognormal fragilities dashed.
pub fn fragility_svg(fragility: &Fragility, x_label: &str) -> String {
    render((760, 500), |root| {
        let range = axis_range(fragility.wind_speeds.iter().copied(), 0.02);
        let Ok(mut chart) = ChartBuilder::on(root)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(range.clone(), 0.0..1.0)
        else {
            return;
        };
        let _ = chart.configure_mesh().x_desc("storm mean wind speed v (m/s)").y_desc("P(peak > x | v)").draw();
        let speeds = &fragility.wind_speeds;
        for (i, curve) in fragility.curves.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let band: Vec<(f64, f64)> = speeds
                .iter()
                .zip(&curve.upper)
                .map(|(v, p)| (*v, *p))
                .chain(speeds.iter().zip(&curve.lower).rev().map(|(v, p)| (*v, *p)))
                .collect();
            let _ = chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15).filled())));
            let line = speeds.iter().zip(&curve.probability).map(|(v, p)| (*v, *p));
            if let Ok(series) = chart.draw_series(LineSeries::new(line, colour.stroke_width(2))) {
                let label = format!("{x_label} > {:.4} m", curve.threshold);
                series
                    .label(label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
            }
            if let Some(fit) = &curve.lognormal {
                let normal = Normal::standard();
                let (lo, hi) = (range.start.max(1e-3), range.end);
                let fitted = (0..=100).map(|k| {
                    let v = lo + (hi - lo) * k as f64 / 100.0;
                    (v, normal.cdf((v / fit.median_speed).ln() / fit.dispersion))
                });
                let _ = chart.draw_series(DashedLineSeries::new(fitted, 6, 4, colour.stroke_width(1)));
            }
        }
        let _ = chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw();
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::exceedance_curve;

    #[test]
    fn axis_ranges_are_finite_whatever_the_values() {
        assert_eq!(axis_range([1.0, 3.0].into_iter(), 0.5), 0.0..4.0);
        assert_eq!(axis_range([f64::NAN, f64::INFINITY].into_iter(), 0.5), 0.0..1.0);
        let huge = axis_range([-1e308, 1e308].into_iter(), 0.02);
        assert!(huge.start.is_finite() && huge.end.is_finite() && huge.start < huge.end);
        let single = axis_range([2.0].into_iter(), 0.1);
        assert!(single.start < 2.0 && single.end > 2.0);
    }

    /// Extreme thresholds once sent plotters' tick search into an endless loop; the figure must
    /// come back (a thread that does not return fails the test instead of hanging it).
    #[test]
    fn extreme_thresholds_still_draw() {
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let curve = exceedance_curve(&[0.1, 0.2, 0.3], &[-1e308, 0.15, 1e308], 0.95);
            let _ = sender.send(exceedance_svg(&[("PC-NARX", &curve)], "x (m)"));
        });
        let svg = receiver.recv_timeout(std::time::Duration::from_secs(20)).expect("the figure is drawn");
        assert!(svg.starts_with("<svg"));
    }
}
