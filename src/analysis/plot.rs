//! SVG figures: exceedance curves with their bands (the paper's Fig. 7) and the scatter of peaks,
//! reference against metamodel (Fig. 6). Text only, no fonts needed.

use super::ExceedanceCurve;
use plotters::prelude::*;

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

/// Exceedance curves with their confidence bands.
pub fn exceedance_svg(curves: &[(&str, &ExceedanceCurve)], x_label: &str) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 480)).into_drawing_area();
        let _ = root.fill(&WHITE);
        draw_curves(&root, curves, x_label);
        let _ = root.present();
    }
    svg
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
