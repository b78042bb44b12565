//! A run's progress curve as the store keeps it: `progress.csv`'s columns `time_s`,
//! `explored_area_m2` and `explored_fraction`, one line per sample, written and read here only
//! (with the `csv` crate).

/// The columns of a stored progress curve.
pub const HEADER: [&str; 3] = ["time_s", "explored_area_m2", "explored_fraction"];

/// One sample of a progress curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Simulated seconds since the start.
    pub time_s: f64,
    pub explored_area_m2: f64,
    pub explored_fraction: f64,
}

impl Sample {
    /// The sample's values by bits, in the columns' order: two samples are stored as the same
    /// line exactly when these are equal.
    pub fn bits(&self) -> [u64; 3] {
        [
            self.time_s.to_bits(),
            self.explored_area_m2.to_bits(),
            self.explored_fraction.to_bits(),
        ]
    }
}

impl From<[f64; 3]> for Sample {
    /// From `[time_s, explored_area_m2, explored_fraction]`.
    fn from([time_s, explored_area_m2, explored_fraction]: [f64; 3]) -> Sample {
        Sample {
            time_s,
            explored_area_m2,
            explored_fraction,
        }
    }
}

/// A progress curve as stored: simulated time to 0.1 s, explored area to 1 cm² (three
/// decimals of m²), explored fraction to five decimals (what the store has always held, so that
/// results of remote workers compare equal to this machine's).
pub fn encode(samples: &[Sample]) -> String {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to memory cannot fail; a record is three plain numbers.
    let _ = w.write_record(HEADER);
    for s in samples {
        let _ = w.write_record([
            format!("{:.1}", s.time_s),
            format!("{:.3}", s.explored_area_m2),
            format!("{:.5}", s.explored_fraction),
        ]);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// `samples` as the store holds them: rounded as [`encode`] writes them, so that a curve made
/// here equals the same curve read back from the store.
pub fn stored(samples: &[Sample]) -> Vec<Sample> {
    // What `encode` writes, `decode` reads.
    decode(&encode(samples)).unwrap_or_default()
}

/// The samples of a stored curve: its header, then three numbers a line. The error names the
/// first line that is not so (line 1 is the header).
pub fn decode(text: &str) -> Result<Vec<Sample>, String> {
    if text.is_empty() {
        return Err("it is empty, expected at least its header".into());
    }
    let mut r = csv::ReaderBuilder::new()
        .flexible(true)
        .has_headers(false)
        .from_reader(text.as_bytes());
    let mut out = Vec::new();
    for (i, record) in r.records().enumerate() {
        let line = i + 1;
        let record = record.map_err(|e| format!("line {line} is not CSV ({e})"))?;
        if line == 1 {
            if record.iter().ne(HEADER) {
                return Err(format!("line 1 is not the header {}", HEADER.join(",")));
            }
            continue;
        }
        let number = |i: usize| record.get(i)?.trim().parse::<f64>().ok();
        match (record.len(), number(0), number(1), number(2)) {
            (3, Some(t), Some(a), Some(f)) => out.push(Sample::from([t, a, f])),
            _ => {
                return Err(format!(
                    "line {line} is not three numbers ({})",
                    HEADER.join(",")
                ))
            }
        }
    }
    Ok(out)
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
        ]
        .map(Sample::from);
        let text = encode(&samples);
        let mut before = String::from("time_s,explored_area_m2,explored_fraction\n");
        for s in samples {
            before.push_str(&format!(
                "{:.1},{:.3},{:.5}\n",
                s.time_s, s.explored_area_m2, s.explored_fraction
            ));
        }
        assert_eq!(text, before);
        let back = decode(&text).unwrap();
        assert_eq!(back.len(), 3);
        assert_eq!(back[1], Sample::from([10.0, 12.346, 0.12346]));
        // Read back, a curve is written again as it was.
        assert_eq!(encode(&back), text);
        assert_eq!(stored(&samples), back);
        assert_eq!(decode(&encode(&[])).unwrap(), vec![]);
    }

    /// A damaged curve is refused, naming its line.
    #[test]
    fn damaged_curves_are_refused_naming_the_line() {
        let cases = [
            (
                "time_s,explored_area_m2,explored_fraction\n1.0,2.0\n",
                "line 2",
            ),
            (
                "time_s,explored_area_m2,explored_fraction\n1,2,3\nx,1,1\n",
                "line 3",
            ),
            (
                "time_s,explored_area_m2,explored_fraction\n1,2,3,4\n",
                "line 2",
            ),
            ("t,a,f\n1,2,3\n", "line 1 is not the header"),
            ("", "empty"),
        ];
        for (text, words) in cases {
            let e = decode(text).unwrap_err();
            assert!(e.contains(words), "{text:?}: {e}");
        }
    }
}
