//! Fuzzing the settings file parser: mutations of a valid settings file never panic and every
//! accepted file is valid. `PROPTEST_CASES` sets how many cases run.

use floorcast_worker::settings::settings_from_json_text;
use proptest::prelude::*;

const SETTINGS: &str = r#"{"alpha": 0.8, "time_limit_s": 600, "localization": "odometry", "laser_beams": 90, "return_home": true, "utility_distance": "euclidean"}"#;

/// The tokens that matter to a settings file.
const TOKENS: [&[u8]; 8] = [b"1e300", b"-1", b"[", b"\"", b"null", b"{", b"1e6", b"0"];

fn mutate(text: &str, edits: &[(usize, u8, u8)]) -> String {
    floorcast_formats::mutation::mutate(text, edits, &TOKENS)
}

proptest! {
    #[test]
    fn settings_files_never_panic(edits in proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 0..10)) {
        let text = mutate(SETTINGS, &edits);
        match settings_from_json_text(&text) {
            Ok(s) => prop_assert!(s.validate().is_ok() && s.to_explore_config().is_ok()),
            Err(e) => {
                let s = e.to_string();
                prop_assert!(!s.contains('\n'), "multi-line: {}", s);
                prop_assert!(s.starts_with("settings"), "{}", s);
            }
        }
    }
}

#[test]
fn the_seed_of_the_fuzzer_is_valid() {
    let s = settings_from_json_text(SETTINGS).unwrap();
    assert_eq!(s.laser_beams, 90);
}
