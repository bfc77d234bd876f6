//! The distance transform is exact: compared with brute force on random masks.

use brume::prep::edt::{squared_edt, NO_SITE};
use brume::raster::Grid;

/// Small xorshift generator for the masks.
fn next(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

fn brute_force(sites: &Grid<bool>) -> Vec<u32> {
    let (w, h) = (sites.width(), sites.height());
    let pts: Vec<(i64, i64)> = (0..w * h)
        .filter(|&i| sites.as_slice()[i])
        .map(|i| ((i % w) as i64, (i / w) as i64))
        .collect();
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            pts.iter()
                .map(|&(px, py)| ((px - x).pow(2) + (py - y).pow(2)) as u32)
                .min()
                .unwrap_or(NO_SITE)
        })
        .collect()
}

#[test]
fn edt_matches_brute_force_on_random_masks() {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    for case in 0..400 {
        let w = 1 + (next(&mut s) % 24) as usize;
        let h = 1 + (next(&mut s) % 24) as usize;
        // Densities from "no site" to "all sites".
        let per_mille = [0, 2, 10, 50, 200, 500, 900, 1000][case % 8];
        let mask = Grid::from_fn(w, h, |_, _| next(&mut s) % 1000 < per_mille);
        let got = squared_edt(&mask);
        assert_eq!(
            got.as_slice(),
            &brute_force(&mask)[..],
            "case {case}: {w}x{h}, {per_mille} per mille"
        );
    }
}

#[test]
fn edt_single_site_and_wide_masks() {
    let mut m = Grid::filled(300, 3, false);
    *m.get_mut(299, 1) = true;
    let d = squared_edt(&m);
    assert_eq!(*d.get(0, 0), 299 * 299 + 1);
    assert_eq!(*d.get(299, 1), 0);
    let none = squared_edt(&Grid::filled(5, 5, false));
    assert!(none.as_slice().iter().all(|&v| v == NO_SITE));
}
