//! SVG figures: exceedance curves with their bands (the paper's Fig. 7) and the scatter of peaks,
//! reference against metamodel (Fig. 6). Text only, no fonts needed.

use super::ExceedanceCurve;
use plotters::prelude::*;

const COLOURS: [RGBColor; 3] = [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44)];

fn draw_curves(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    curves: &[(&str, &ExceedanceCurve)],
    x_label: &str,
) {
    let (lo, hi) = curves
        .iter()
        .flat_map(|(_, c)| c.thresholds.iter())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    let Ok(mut chart) = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(lo - 0.02 * span..hi + 0.02 * span, 0.0..1.0)
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
        let hi = reference.iter().chain(metamodel).fold(0.0f64, |m, v| m.max(*v)) * 1.05;
        let lo = reference.iter().chain(metamodel).fold(f64::INFINITY, |m, v| m.min(*v)) * 0.95;
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
