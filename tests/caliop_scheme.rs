//! The `caliop` onboard scheme gives each channel its own layout: CALIOP's 1064 nm
//! channel is not downlinked above 30.1 km and has 60 m bins from −0.5 to 8.2 km (Hunt et
//! al. 2009, J. Atmos. Oceanic Technol. 26, 1214, Table 2; Winker et al. 2009, ibid.
//! 2310; CALIPSO Data Products Catalog PC-SCI-503, Lidar Level 1B). The table below is
//! the reference, written here from those sources:
//!
//! | altitudes (km) | 532 nm (∥, ⊥)   | 1064 nm        | shots |
//! |----------------|-----------------|----------------|-------|
//! | 30.1–40.0      | 300 m, 33 bins  | none           | 15    |
//! | 20.2–30.1      | 180 m, 55 bins  | 180 m, 55 bins | 5     |
//! | 8.2–20.2       | 60 m, 200 bins  | 60 m, 200 bins | 3     |
//! | −0.5–8.2       | 30 m, 290 bins  | 60 m, 145 bins | 1     |
//! | −2.0–−0.5      | 300 m, 5 bins   | 300 m, 5 bins  | 1     |

mod common;

use lidarsim::onboard::Scheme;

/// (top, bottom, resolution m, bins, shots) per channel kind.
const TABLE_532: [(f64, f64, f64, usize, u32); 5] = [
    (40.0, 30.1, 300.0, 33, 15),
    (30.1, 20.2, 180.0, 55, 5),
    (20.2, 8.2, 60.0, 200, 3),
    (8.2, -0.5, 30.0, 290, 1),
    (-0.5, -2.0, 300.0, 5, 1),
];
const TABLE_1064: [(f64, f64, f64, usize, u32); 4] = [
    (30.1, 20.2, 180.0, 55, 5),
    (20.2, 8.2, 60.0, 200, 3),
    (8.2, -0.5, 60.0, 145, 1),
    (-0.5, -2.0, 300.0, 5, 1),
];

const WINDOW: [&str; 2] = [
    "acquisition.top_altitude_km=40",
    "acquisition.bottom_altitude_km=-2",
];

/// The rows of the table that hold channel `c` of the three-channel instrument.
fn table_of(c: usize) -> &'static [(f64, f64, f64, usize, u32)] {
    if c == 2 { &TABLE_1064 } else { &TABLE_532 }
}

/// Every channel's layout: per channel the (top, bottom, resolution, bins, shots) of the
/// regions that hold it, and the native bins each merges (≈ resolution / 29.93 m).
#[test]
fn each_channel_has_calipsos_layout() {
    let lidar = common::lidar("instruments/caliop_3ch.toml", &WINDOW);
    let wavelengths: Vec<f64> = lidar
        .channels
        .iter()
        .map(|c| c.instrument.wavelength_nm)
        .collect();
    assert_eq!(wavelengths, [532.0, 532.0, 1064.0]);
    let g = &lidar.first().geometry;
    let native_vertical = g.bin_range_m * g.local_cos_at(0.0);
    let l = Scheme::parse("caliop")
        .unwrap()
        .channel_layout(
            &wavelengths,
            g.n_bins,
            &|i| g.bin_centre_altitude_m(i),
            native_vertical,
        )
        .unwrap();
    for c in 0..3 {
        let held: Vec<_> = l
            .iter()
            .filter(|r| r.channel_indices(3).contains(&c))
            .collect();
        let got: Vec<(f64, f64, f64, usize, u32)> = held
            .iter()
            .map(|r| {
                let reg = r.region.as_ref().unwrap();
                (
                    reg.top_km,
                    reg.bottom_km,
                    reg.vertical_resolution_m,
                    r.bins,
                    r.shots,
                )
            })
            .collect();
        assert_eq!(got, table_of(c), "channel {c}");
        for (r, row) in held.iter().zip(table_of(c)) {
            assert_eq!(r.merge, (row.2 / 29.93f64).round() as usize);
        }
        // contiguous from the top of the channel's layout down
        for w in held.windows(2) {
            assert_eq!(w[1].first_bin, w[0].first_bin + w[0].merge * w[0].bins);
        }
    }
    // the 1064 layout starts on the bin where the 532 layout's 30.1 km region starts
    let start = |c: usize| {
        l.iter()
            .find(|r| {
                r.channel_indices(3).contains(&c) && r.region.as_ref().unwrap().top_km == 30.1
            })
            .unwrap()
            .first_bin
    };
    assert_eq!(start(0), start(2));
    let bins = |c: usize| table_of(c).iter().map(|r| r.3).sum::<usize>();
    assert_eq!((bins(0), bins(2)), (583, 405));
}

/// The product has one group per region, its `channel` dimension listing the channels
/// the region holds; the 1064 nm 60 m region sums pairs of native bins of the 1064
/// channel exactly (checked against the native raw file of the same draw); the report's
/// `data_rate_bps` is each channel's bins per shot times 16 bits times 20.16 Hz, computed
/// here from the table (315.27 kbit/s, within 0.3 % of CALIOP's 316 kbit/s; the old
/// layout, 583 bins for all three channels, gave 362.75 kbit/s).
#[test]
fn the_product_and_data_rate_follow_each_channels_layout() {
    let dir = std::env::temp_dir().join(format!("lidarsim-caliop-scheme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = common::config_path("instruments/caliop_3ch.toml");
    let (product, raw) = (dir.join("p.h5"), dir.join("raw.h5"));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(["onboard", cfg.to_str().unwrap(), "--scheme", "caliop"])
        .args(WINDOW.iter().flat_map(|w| ["--set", w]))
        .args([
            "--set",
            "acquisition.profiles=2",
            "--seed",
            "9",
            "-o",
            product.to_str().unwrap(),
            "--raw",
            raw.to_str().unwrap(),
            "--report",
            "-",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = String::from_utf8(o.stdout).unwrap();
    // the data rate, from the table
    let per_shot: f64 = (0..3)
        .flat_map(|c| table_of(c).iter().map(|r| r.3 as f64 / f64::from(r.4)))
        .sum();
    let want = per_shot * 16.0 * 20.16;
    assert!((want - 315_270.144).abs() < 1e-6, "{want}");
    assert!((want / 316e3 - 1.0).abs() < 0.003);
    let rows: Vec<&str> = report.lines().skip(1).collect();
    assert_eq!(rows.len(), 6, "{report}");
    for row in &rows {
        let rate: f64 = row.split(',').nth(9).unwrap().parse().unwrap();
        assert!((rate / want - 1.0).abs() < 1e-12, "{row}");
    }
    // the groups and their channels
    let f = hdf5::File::open(&product).unwrap();
    let names = |k: usize| -> Vec<String> {
        f.dataset(&format!("region_{k}/channel_name"))
            .unwrap()
            .read_raw::<hdf5::types::VarLenUnicode>()
            .unwrap()
            .iter()
            .map(|s| s.as_str().to_string())
            .collect()
    };
    let all = ["532_parallel", "532_perpendicular", "1064_total"];
    let want_groups: [(&[&str], f64, usize); 6] = [
        (&all[..2], 300.0, 33),
        (&all, 180.0, 55),
        (&all, 60.0, 200),
        (&all[..2], 30.0, 290),
        (&all[2..], 60.0, 145),
        (&all, 300.0, 5),
    ];
    for (k, (channels, res, bins)) in want_groups.iter().enumerate() {
        assert_eq!(names(k), *channels, "region_{k}");
        let g = f.group(&format!("region_{k}")).unwrap();
        let r: f64 = g
            .attr("vertical_resolution_m")
            .unwrap()
            .read_scalar()
            .unwrap();
        assert_eq!(r, *res);
        let shape = g.dataset("counts").unwrap().shape();
        assert_eq!(shape[1..], [channels.len(), *bins]);
    }
    assert!(f.group("region_6").is_err());
    // region_4 (1064 nm, 60 m, 1 shot) sums pairs of the native 1064 bins from where the
    // 532 nm 30 m region starts
    let raw = hdf5::File::open(&raw).unwrap();
    let ds = raw.dataset("counts").unwrap();
    let shape = ds.shape();
    let native: Vec<u64> = ds.read_raw::<u64>().unwrap_or_else(|_| {
        ds.read_raw::<u16>()
            .unwrap()
            .into_iter()
            .map(u64::from)
            .collect()
    });
    let (n_channels, n_bins) = (shape[1], shape[2]);
    let alt: Vec<f64> = raw.dataset("altitude").unwrap().read_raw().unwrap();
    // region_3's first bin is one native bin: its altitude names it
    let top3: f64 = f
        .dataset("region_3/altitude")
        .unwrap()
        .read_raw::<f64>()
        .unwrap()[0];
    let first = (0..n_bins).position(|i| alt[i] == top3).unwrap();
    // (8.26 km: the regions are laid from 40 km down on the 29.93 m vertical grid)
    assert!((top3 - 8.2e3).abs() < 100.0, "{top3}");
    let product_counts: Vec<u32> = f.dataset("region_4/counts").unwrap().read_raw().unwrap();
    let region3: Vec<u32> = f.dataset("region_3/counts").unwrap().read_raw().unwrap();
    let shots = product_counts.len() / 145;
    assert_eq!(shots, 30);
    let mut checked = 0;
    for p in 0..shots {
        for j in 0..145 {
            let at = |c: usize, i: usize| native[(p * n_channels + c) * n_bins + i];
            let pair = at(2, first + 2 * j) + at(2, first + 2 * j + 1);
            assert_eq!(
                u64::from(product_counts[p * 145 + j]),
                pair,
                "shot {p} bin {j}"
            );
            // and region_3 is the 532 channels' native bins
            for c in 0..2 {
                let k = (p * 2 + c) * 290 + 2 * j;
                assert_eq!(u64::from(region3[k]), at(c, first + 2 * j));
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 30 * 145);
    std::fs::remove_dir_all(&dir).ok();
}
