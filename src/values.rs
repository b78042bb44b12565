//! Parsers of the command line's numbers whose errors say what was expected (clap's own say how
//! the text failed to parse: "invalid digit found in string", "invalid float literal"). clap puts
//! the flag and the value before the message: `invalid value 'x' for '--seed <SEED>': expected a
//! whole number from 0 to 18446744073709551615`.

/// Most threads a machine's `run --workers` or `worker --jobs` may ask for: each runs an
/// exploration at once (up to about 200 MB each), and a count beyond what the system allows
/// would fail to start threads rather than run.
pub const MAX_THREADS: u64 = 1024;

/// A whole number from `lo` to `hi` (both included), as `T`.
pub fn whole_number<T: TryFrom<u64>>(
    lo: u64,
    hi: u64,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        s.trim()
            .parse::<u64>()
            .ok()
            .filter(|v| (lo..=hi).contains(v))
            .and_then(|v| T::try_from(v).ok())
            .ok_or_else(|| format!("expected a whole number from {lo} to {hi}"))
    }
}

/// One of the words of a setting's choice (`all`, each written `as_str`): clap offers, checks
/// and suggests exactly these words (`[possible values: ...]`), the words files and records use.
pub fn word_choice<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    as_str: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(all.iter().map(|&v| as_str(v))).try_map(
        move |word: String| {
            all.iter()
                .copied()
                .find(|&v| as_str(v) == word)
                .ok_or_else(|| format!("'{word}' is none of the words of this choice"))
        },
    )
}

/// A finite number (its range is the flag's own check, which names the range).
pub fn number(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err("expected a finite number".into()),
        Err(_) => Err("expected a number, e.g. 2.5 or 1e3".into()),
    }
}

/// A printed length with its unit, in inches: `3.5in`, `8.9cm`, `89mm` or `252pt`, from 1 to 20
/// inches (a figure's width).
pub fn length_in(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let expected = || {
        "expected a length with its unit from 1 to 20 inches, e.g. 3.5in, 8.9cm, 89mm or 252pt"
            .to_string()
    };
    let (number, per_inch) = [("in", 1.0), ("cm", 2.54), ("mm", 25.4), ("pt", 72.0)]
        .iter()
        .find_map(|(unit, per)| t.strip_suffix(unit).map(|n| (n.trim(), *per)))
        .ok_or_else(expected)?;
    let v: f64 = number.parse().map_err(|_| expected())?;
    let inches = v / per_inch;
    (inches.is_finite() && (1.0..=20.0).contains(&inches))
        .then_some(inches)
        .ok_or_else(expected)
}

/// The cores of this machine (1 when unknown): the default number of worker threads.
pub fn cores() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_carry_their_unit() {
        for (text, want) in [
            ("3.5in", Some(3.5)),
            (" 8.89cm ", Some(3.5)),
            ("89 mm", Some(89.0 / 25.4)),
            ("252pt", Some(3.5)),
            ("3.5", None),
            ("0.5in", None),
            ("30in", None),
            ("NaNin", None),
            ("in", None),
        ] {
            let got = length_in(text).ok();
            assert!(
                match (got, want) {
                    (Some(g), Some(w)) => (g - w).abs() < 1e-9,
                    (None, None) => true,
                    _ => false,
                },
                "{text}: {got:?}"
            );
        }
    }

    #[test]
    fn numbers_are_parsed_or_refused_saying_what_was_expected() {
        let seed = whole_number::<u64>(0, u64::MAX);
        let workers = whole_number::<usize>(0, MAX_THREADS);
        let cells = whole_number::<u64>(1, 4_000_000_000);
        fn whole_err<T>(lo: u64, hi: u64) -> Result<T, String> {
            Err(format!("expected a whole number from {lo} to {hi}"))
        }
        for (text, want) in [
            ("0", Ok(0)),
            (" 7 ", Ok(7)),
            ("18446744073709551615", Ok(u64::MAX)),
            ("18446744073709551616", whole_err(0, u64::MAX)),
            ("-1", whole_err(0, u64::MAX)),
            ("1.5", whole_err(0, u64::MAX)),
            ("abc", whole_err(0, u64::MAX)),
            ("", whole_err(0, u64::MAX)),
        ] {
            assert_eq!(seed(text), want, "{text:?}");
        }
        assert_eq!(workers("1024"), Ok(1024));
        assert_eq!(workers("1025"), whole_err(0, MAX_THREADS));
        assert_eq!(cells("0"), whole_err(1, 4_000_000_000));
        assert_eq!(cells("4000000000"), Ok(4_000_000_000));
        for (text, want) in [
            ("2.5", Ok(2.5)),
            ("-5", Ok(-5.0)),
            ("1e300", Ok(1e300)),
            ("inf", Err("expected a finite number".to_string())),
            ("NaN", Err("expected a finite number".to_string())),
            ("1e400", Err("expected a finite number".to_string())),
            (
                "five",
                Err("expected a number, e.g. 2.5 or 1e3".to_string()),
            ),
        ] {
            assert_eq!(number(text), want, "{text:?}");
        }
    }

    /// A word choice's parser accepts exactly the enum's words, each as its value, and offers
    /// them in `ALL`'s order.
    #[test]
    fn word_choices_take_the_words_of_all() {
        use clap::builder::TypedValueParser as _;
        use floorcast_worker::settings::{LocalizationSetting, UtilityDistanceSetting};
        let cmd = clap::Command::new("t");
        let parser = word_choice(&LocalizationSetting::ALL, LocalizationSetting::as_str);
        let offered: Vec<String> = parser
            .possible_values()
            .unwrap()
            .map(|v| v.get_name().to_string())
            .collect();
        assert_eq!(offered, ["slam", "odometry", "ground-truth"]);
        for v in LocalizationSetting::ALL {
            assert_eq!(
                parser.parse_ref(&cmd, None, v.as_str().as_ref()).ok(),
                Some(v)
            );
        }
        for bad in ["", "SLAM", "ground_truth", "slam "] {
            assert!(
                parser.parse_ref(&cmd, None, bad.as_ref()).is_err(),
                "{bad:?}"
            );
        }
        let parser = word_choice(&UtilityDistanceSetting::ALL, UtilityDistanceSetting::as_str);
        for v in UtilityDistanceSetting::ALL {
            assert_eq!(
                parser.parse_ref(&cmd, None, v.as_str().as_ref()).ok(),
                Some(v)
            );
        }
        assert!(parser.parse_ref(&cmd, None, "Path".as_ref()).is_err());
    }
}
