//! A run's progress curve as the store keeps it: `progress.csv`'s columns `time_s`,
//! `explored_area_m2` and `explored_fraction`, one line per sample, written and read here only
//! (with the `csv` crate).

/// The columns of a stored progress curve.
pub const HEADER: [&str; 3] = ["time_s", "explored_area_m2", "explored_fraction"];

/// A progress curve as stored: simulated time to 0.1 s, explored area to 1 cm² (three
/// decimals of m²), explored fraction to five decimals (what the store has always held, so that
/// results of remote workers compare equal to this machine's).
pub fn encode(samples: &[[f64; 3]]) -> String {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to memory cannot fail; a record is three plain numbers.
    let _ = w.write_record(HEADER);
    for [t, area, fraction] in samples {
        let _ = w.write_record([
            format!("{t:.1}"),
            format!("{area:.3}"),
            format!("{fraction:.5}"),
        ]);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// The samples `(time_s, explored_area_m2, explored_fraction)` of a stored curve; lines that do
/// not hold three numbers are skipped.
pub fn decode(text: &str) -> impl Iterator<Item = [f64; 3]> + '_ {
    csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes())
        .into_records()
        .filter_map(|r| {
            let r = r.ok()?;
            let number = |i: usize| r.get(i)?.trim().parse::<f64>().ok();
            Some([number(0)?, number(1)?, number(2)?])
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The curve is stored as it always was, and reads back as what was stored.
    #[test]
    fn curves_are_stored_as_before_and_read_back() {
        let samples = [
            [0.0, 0.0, 0.0],
            [10.04, 12.3456, 0.123456],
            [606.25, 407.98, 0.99944],
        ];
        let text = encode(&samples);
        let mut before = String::from("time_s,explored_area_m2,explored_fraction\n");
        for [t, area, fraction] in samples {
            before.push_str(&format!("{t:.1},{area:.3},{fraction:.5}\n"));
        }
        assert_eq!(text, before);
        let back: Vec<[f64; 3]> = decode(&text).collect();
        assert_eq!(back.len(), 3);
        assert_eq!(back[1], [10.0, 12.346, 0.12346]);
        // Damaged lines are skipped, the others read.
        let damaged = "time_s,explored_area_m2,explored_fraction\n1.0,2.0\nx,1,1\n3.0,4.0,0.5\n";
        assert_eq!(decode(damaged).collect::<Vec<_>>(), vec![[3.0, 4.0, 0.5]]);
        assert_eq!(decode("").count(), 0);
    }
}
