//! The figures' colours: one per engine, from Okabe and Ito's colour-blind-safe palette, the
//! same in every figure; the exact solutions in greys, drawn thick under the engines.

use plotters::style::RGBColor;

/// Okabe–Ito blue.
pub const BLUE: RGBColor = RGBColor(0, 114, 178);
/// Okabe–Ito sky blue.
pub const SKY_BLUE: RGBColor = RGBColor(86, 180, 233);
/// Okabe–Ito vermillion.
pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
/// Okabe–Ito reddish purple.
pub const PURPLE: RGBColor = RGBColor(204, 121, 167);
/// Okabe–Ito orange.
pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
/// Okabe–Ito bluish green.
pub const GREEN: RGBColor = RGBColor(0, 158, 115);
/// Okabe–Ito yellow.
pub const YELLOW: RGBColor = RGBColor(240, 228, 66);
/// The closed form, drawn thickest and lightest.
pub const CLOSED_FORM: RGBColor = RGBColor(190, 190, 190);
/// The converged reference, drawn thick over the closed form.
pub const REFERENCE: RGBColor = RGBColor(120, 120, 120);

/// An engine's colour (black for an engine this palette does not know).
pub fn engine(name: &str) -> RGBColor {
    match name {
        "explicit" => BLUE,
        "explicit_small" => SKY_BLUE,
        "rapier_f64" => VERMILLION,
        "rapier_f32" => PURPLE,
        "rapier_f64_default" => ORANGE,
        "rapier_f32_default" => GREEN,
        "analytic" => CLOSED_FORM,
        "reference" => REFERENCE,
        _ => RGBColor(0, 0, 0),
    }
}

/// Whether an engine is an exact solution (drawn thick and grey, under the engines).
pub fn is_exact(name: &str) -> bool {
    crate::comparison::EXACT_SOLUTIONS.contains(&name)
}
