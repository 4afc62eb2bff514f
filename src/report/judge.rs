//! What `crosscheck judge` prints: where their rows fell, and per column the error against the
//! exact solution with the verdict, as markdown.

use crate::comparison::judge::{External, Resampling};
use crate::comparison::{Comparison, verdict};
use crate::report::format::sci;

/// The judgement as markdown: a line on the resampling, a table per column (their column, the
/// unit, the factor applied, the largest and RMS error over the peak, within the tolerance or
/// not) and the verdict.
pub fn render(
    case: &str,
    against: &str,
    external: &External,
    resampling: &Resampling,
    comparison: &Comparison,
    tolerance: f64,
) -> String {
    let mut s = format!(
        "{case} against `{against}`: {} output times, {} on one of their rows and {} \
         interpolated linearly between two; their rows {} to {} used (of {}).\n\n",
        resampling.on_a_row + resampling.interpolated,
        resampling.on_a_row,
        resampling.interpolated,
        resampling.rows_used.0,
        resampling.rows_used.1,
        external.times.len()
    );
    s += "| column | their column | unit | factor | max error / peak | RMS / peak | within ";
    s += &format!("{} |\n|---|---|---|---:|---:|---:|---|\n", sci(tolerance));
    for c in &comparison.columns {
        let (theirs, factor) = external
            .columns
            .iter()
            .find(|x| x.0 == c.column)
            .map_or(("–".to_string(), 1.0), |x| (x.1.clone(), x.2));
        let (max, rms, verdict) = if c.relative {
            let ok = if verdict::within(c.max, tolerance) {
                "yes"
            } else {
                "**no**"
            };
            (sci(c.max), sci(c.rms), ok.to_string())
        } else {
            // The exact column is zero over the rows compared: the error is absolute.
            let abs = format!("{} {} (absolute)", sci(c.max), c.unit);
            (abs, sci(c.rms), "not judged (exact value 0)".to_string())
        };
        s += &format!(
            "| {} | {theirs} | {} | {factor} | {max} | {rms} | {verdict} |\n",
            c.column, c.unit
        );
    }
    s += &match comparison.worst_max {
        Some(w) if verdict::within(w, tolerance) => format!(
            "\nPASS: the largest error is {} of the peak, within {}.\n",
            sci(w),
            sci(tolerance)
        ),
        Some(w) => {
            let failing: Vec<&str> = comparison
                .columns
                .iter()
                .filter(|c| c.relative && c.max > tolerance)
                .map(|c| c.column.as_str())
                .collect();
            format!(
                "\nFAIL: {} over {} (largest: {} of the peak).\n",
                failing.join(", "),
                sci(tolerance),
                sci(w)
            )
        }
        None => "\nNo column has a peak to judge against.\n".to_string(),
    };
    s
}
