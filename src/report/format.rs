//! How the report writes numbers: in its pages ([`sci`]), on figure axes and labels
//! ([`tick`]) and in its CSV files ([`csv_value`]). Every module of the report formats numbers
//! through this one.

/// A number as the report prints it.
pub fn sci(x: f64) -> String {
    format!("{x:.2e}")
}

/// [`sci`] for a number that may be missing, a dash where it is.
pub fn sci_or_dash(x: Option<f64>) -> String {
    x.map_or("–".into(), sci)
}

/// A tick label: at most 3 significant digits, trailing zeros dropped, and a value within
/// 1e-6 of the axis span of zero printed as 0 (no round-off noise such as `-1.388e-17`).
pub fn tick(y: f64, span: f64) -> String {
    if y.abs() <= 1e-6 * span.abs() || y == 0.0 {
        return "0".into();
    }
    let a = y.abs();
    if (1e-3..1e4).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        let text = format!("{y:.decimals$}");
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            text
        }
    } else {
        let text = format!("{y:.2e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let mantissa = if mantissa.contains('.') {
            mantissa.trim_end_matches('0').trim_end_matches('.')
        } else {
            mantissa
        };
        format!("{mantissa}e{exponent}")
    }
}

/// A time as the report prints it: six significant digits, without the round-off of summing
/// increments (0.5274, not 0.5274000000000001).
pub fn instant(t: f64) -> String {
    let rounded: f64 = format!("{t:.5e}").parse().unwrap_or(t);
    format!("{rounded}")
}

/// Format a number as the CSV stores it: shortest round-trip scientific notation.
pub fn csv_value(x: f64) -> String {
    format!("{x:e}")
}

/// [`csv_value`] for a finite number, an empty field otherwise (tables where a value may be
/// missing: the scaling study, the sweep).
pub fn csv_finite(x: f64) -> String {
    if x.is_finite() {
        csv_value(x)
    } else {
        String::new()
    }
}

/// A CSV table: the header, then one record per row (quoted where a field needs it).
pub fn csv_table(columns: &[&str], rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(columns);
    for row in rows {
        let _ = w.write_record(&row);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// A ratio as tables print it: two significant digits below 10, whole numbers to 1000, then
/// scientific (0.25, 1.5, 21, 376, 1.5e3).
pub fn ratio(x: f64) -> String {
    if x < 0.1 {
        format!("{x:.1e}")
    } else if x < 10.0 {
        format!("{}", (x * 100.0).round() / 100.0)
    } else if x < 1e3 {
        format!("{x:.0}")
    } else {
        format!("{x:.1e}")
    }
}

/// A figure's markdown image link, followed by a blank line; nothing in a build without the
/// figures (the cargo feature `figures`), which writes none.
pub fn figure(alt: &str, path: &str) -> String {
    if cfg!(feature = "figures") {
        format!("![{alt}]({path})\n\n")
    } else {
        String::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_instant_keeps_six_significant_digits() {
        assert_eq!(instant(0.5274000000000001), "0.5274");
        assert_eq!(instant(1.0e-5), "0.00001");
        assert_eq!(instant(12.345678), "12.3457");
        assert_eq!(instant(0.0), "0");
    }

    #[test]
    fn tick_labels_have_three_significant_digits_and_no_round_off_noise() {
        assert_eq!(tick(-1.388e-17, 0.3), "0");
        assert_eq!(tick(0.05, 0.3), "0.05");
        assert_eq!(tick(0.125, 0.3), "0.125");
        assert_eq!(tick(-0.2, 0.3), "-0.2");
        assert_eq!(tick(250_000.0, 3e5), "2.5e5");
        assert_eq!(tick(1.2345e-5, 1e-4), "1.23e-5");
        assert_eq!(tick(37.0, 100.0), "37");
    }
}
