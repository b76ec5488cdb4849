//! Axis ticks: round steps (1, 2 or 5 times a power of ten), the tick positions inside a
//! window, the unit the numbers are written in and their labels; and number formatting for
//! labels (three significant digits).

/// A round length (m) at most `target`: 1, 2 or 5 times a power of ten (the perspective
/// view's axis triad).
pub(super) fn round_length(target: f64) -> f64 {
    let power = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * power)
        .find(|&l| l <= target)
        .unwrap_or(power)
}

/// The tick step for about `count` ticks over `span` (m), at least `least` (m): of the
/// steps 1, 2 or 5 times a power of ten that are at least `least`, the nearest to
/// `span / count` in ratio.
pub(super) fn tick_step(span: f64, count: f64, least: f64) -> f64 {
    let target = (span / count).max(least).max(f64::MIN_POSITIVE);
    let power = 10f64.powf(target.log10().floor());
    // 1e-9: a step equal to `least` up to rounding is allowed.
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|k| k * power)
        .filter(|&l| l >= least * (1.0 - 1e-9))
        .min_by(|a, b| (a / target).ln().abs().total_cmp(&(b / target).ln().abs()))
        .unwrap_or(10.0 * power)
}

/// Multiples of `step` inside [lo, hi] (m).
pub(super) fn ticks(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    // 1e-9 steps: a tick that falls on the window's edge up to rounding is kept.
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// The unit tick numbers are written in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Unit {
    /// Its name in axis labels.
    pub name: &'static str,
    /// Numbers per metre.
    pub per_metre: f64,
}

/// Millimetres for scenes up to 10 m across (robots), metres beyond.
pub(super) fn unit_for(extent: f64) -> Unit {
    if extent < 10.0 {
        Unit {
            name: "mm",
            per_metre: 1e3,
        }
    } else {
        Unit {
            name: "m",
            per_metre: 1.0,
        }
    }
}

/// A tick number: `value` (m) in `unit`, with as many decimals as `step` (m) needs.
pub(super) fn tick_label(value: f64, step: f64, unit: Unit) -> String {
    let step = step * unit.per_metre;
    // 1e-9: a step of exactly 10^-k needs k decimals, not k + 1 through rounding.
    let decimals = (-(step.log10() + 1e-9).floor()).max(0.0) as usize;
    let text = format!("{:.*}", decimals, value * unit.per_metre);
    // -0 reads as 0.
    if text.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
        text.trim_start_matches('-').to_string()
    } else {
        text
    }
}

/// `x` to three significant digits without trailing zeros: 0.196, 4.91, 12.3, 1230; below
/// 1e-3 in scientific notation (6.12e-13), never a long run of zeros.
pub fn significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{}", x + 0.0);
    }
    if x.abs() < 1e-3 {
        let text = format!("{x:.2e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}e{exponent}");
    }
    let decimals = (2.0 - x.abs().log10().floor()).max(0.0) as usize;
    let text = format!("{:.*}", decimals, x);
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    };
    if decimals == 0 {
        // Round large numbers to three significant digits too.
        let power = 10f64.powf(x.abs().log10().floor() - 2.0);
        format!("{}", (x / power).round() * power)
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits_never_print_float_noise() {
        for (x, text) in [
            (0.196, "0.196"),
            (4.91, "4.91"),
            (1234.0, "1230"),
            (6.12e-16, "6.12e-16"),
            (-0.0, "0"),
            (-5.0, "-5"),
        ] {
            assert_eq!(significant(x), text);
        }
    }

    #[test]
    fn round_lengths_are_one_two_five() {
        for (target, round) in [(0.06, 0.05), (0.025, 0.02), (0.0013, 0.001), (7.0, 5.0)] {
            // 1e-12: powers of ten are not exact in binary
            assert!((round_length(target) / round - 1.0).abs() < 1e-12, "{target}");
        }
    }

    #[test]
    fn tick_steps_are_the_nearest_one_two_five() {
        for (span, least, step) in [
            (0.5, 0.0, 0.1),
            (0.45, 0.0, 0.1),
            (0.3, 0.0, 0.05),
            (0.26, 0.0, 0.05),
            (0.011, 0.0, 0.002),
            (0.1, 0.0, 0.02),
            (0.3, 0.06, 0.1),
            (0.3, 0.05, 0.05),
        ] {
            // 1e-12: powers of ten are not exact in binary
            assert!(
                (tick_step(span, 5.0, least) / step - 1.0).abs() < 1e-12,
                "{span} {least}"
            );
        }
    }

    #[test]
    fn ticks_cover_the_window_including_its_edges() {
        let t = ticks(-0.2, 0.3, 0.1);
        assert_eq!(t.len(), 6, "{t:?}");
        // 1e-15 m: k * 0.1 is exact to rounding
        assert!((t[0] + 0.2).abs() < 1e-15 && (t[5] - 0.3).abs() < 1e-15, "{t:?}");
    }

    #[test]
    fn tick_labels_have_the_decimals_the_step_needs() {
        let mm = unit_for(0.5);
        assert_eq!(tick_label(0.1, 0.05, mm), "100");
        assert_eq!(tick_label(-0.0, 0.05, mm), "0");
        assert_eq!(tick_label(0.0025, 0.0005, mm), "2.5");
        assert_eq!(tick_label(-1e-18, 0.02, mm), "0");
        assert_eq!(unit_for(500.0).name, "m");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(significant(0.196), "0.196");
        assert_eq!(significant(4.91), "4.91");
        assert_eq!(significant(5.0), "5");
        assert_eq!(significant(0.098_000_1), "0.098");
        assert_eq!(significant(12345.0), "12300");
        assert_eq!(significant(-0.47), "-0.47");
    }
}
