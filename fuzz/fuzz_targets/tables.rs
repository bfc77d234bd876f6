//! The CSV tables a user gives: byte 0 picks the layered fog's density table
//! (`DensityTable::parse_csv`, `--table`) or the camera's spectral sensitivity
//! (`Sensitivity::parse_csv`, `--sensitivity`); the rest is the file, read as UTF-8. An
//! accepted density table has heights strictly increasing and finite extinctions ≥ 0;
//! every error must name the file.
#![no_main]

use std::path::Path;

use brume::atmosphere::Sensitivity;
use brume::medium::DensityTable;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let path = Path::new("data/table.csv");
    let result = if which % 2 == 0 {
        DensityTable::parse_csv(text, path).map(|table| {
            let (heights, extinction) = (table.heights(), table.extinction());
            assert_eq!(heights.len(), extinction.len());
            assert!(heights.windows(2).all(|w| w[0] < w[1]), "{heights:?}");
            assert!(heights.iter().all(|h| h.is_finite()), "{heights:?}");
            assert!(
                extinction.iter().all(|e| e.is_finite() && *e >= 0.0),
                "{extinction:?}"
            );
            let top = heights[heights.len() - 1];
            assert!(table.integral(top + 1.0).is_finite());
        })
    } else {
        Sensitivity::parse_csv(text, path).map(|_| ())
    };
    if let Err(e) = result {
        let msg = e.to_string();
        assert!(msg.starts_with("data/table.csv"), "{msg}");
    }
});
