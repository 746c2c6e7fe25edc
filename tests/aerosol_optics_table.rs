//! ECMWF's aerosol optics table (`aerosol_ifs_rrtm_*.nc`) read by
//! `atmosphere::aerosol_optics_table` on the made-up fixture in its layout
//! (`configs/fields/aerosol_optics_like_ifs.nc`, `tools/make_aerosol_optics_table.py`):
//! every species' optics equal the script's formulas (recomputed here, not through the
//! code under test), the RH bin rule at the bins' edges, RH from q, T, p against a hand
//! value, and one-line refusals of damaged copies naming the file and the variable.
//!
//! `ecmwf_file_reads` (ignored: run with `--ignored` and `LIDARSIM_IFS_AEROSOL_TABLE`
//! set to ECMWF's own file) reads that file too (no number of it is in this repository).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use lidarsim::atmosphere::aerosol_optics_table::AerosolOpticsTable;
use lidarsim::atmosphere::aerosol_species::{
    CAMS_SPECIES, CamsSpecies, IfsType, particle_depolarization, relative_humidity_over_water,
};
use netcdf3::{DataSet, DataVector, FileReader, FileWriter};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/fields/aerosol_optics_like_ifs.nc")
}

/// The fixture script's wavelengths (m) and RH bin bounds.
const WAVELENGTH_M: [f64; 4] = [355e-9, 532e-9, 865e-9, 1064e-9];
const RH_LOWER: [f64; 12] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95];

fn rh_upper(r: usize) -> f64 {
    if r + 1 < RH_LOWER.len() {
        RH_LOWER[r + 1]
    } else {
        1.0
    }
}

/// The script's made-up hydrophilic optics of type `t` (1-based), RH bin `r`, at `wl`,
/// rounded to float32 as the file stores them.
fn philic(t: usize, r: usize, wl: f64) -> (f64, f64) {
    let (t, h, x) = (t as f64, 0.5 * (RH_LOWER[r] + rh_upper(r)), wl / 532e-9);
    let k = (200.0 + 50.0 * t) * (1.0 - 0.9 * h).powf(-0.5) * x.powf(-(0.2 + 0.1 * t));
    let s = 20.0 + 3.0 * t + 10.0 * h + 5.0 * x;
    (k as f32 as f64, s as f32 as f64)
}

/// The script's made-up hydrophobic optics of type `t` (1-based) at `wl`.
fn phobic(t: usize, wl: f64) -> (f64, f64) {
    let (t, x) = (t as f64, wl / 532e-9);
    let k = (100.0 + 40.0 * t) * x.powf(-(0.1 + 0.05 * t));
    ((k as f32) as f64, (30.0 + 2.0 * t + 4.0 * x) as f32 as f64)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn every_species_reads_the_scripts_numbers_at_every_wavelength_and_rh_bin() {
    let table = AerosolOpticsTable::read(&fixture()).unwrap();
    assert_eq!(table.rh_lower.len(), 12);
    assert_eq!((table.n_hydrophilic, table.n_hydrophobic), (10, 14));
    let mut checked = 0;
    for s in CAMS_SPECIES.iter().filter(|s| s.ifs_type.is_some()) {
        for &wl in &WAVELENGTH_M {
            for (r, lo) in RH_LOWER.iter().enumerate() {
                // an RH inside bin r: its middle
                let rh = 0.5 * (lo + rh_upper(r));
                let (k, lr) = table.optics(s, rh, wl).unwrap();
                let (k0, lr0) = match s.ifs_type.unwrap() {
                    IfsType::Hydrophilic(t) => philic(t, r, wl),
                    IfsType::Hydrophobic(t) => phobic(t, wl),
                };
                // float32 in the file, the formulas in f64 rounded to f32: equal to 1e-6
                assert!(
                    close(k, k0, 1e-6) && close(lr, lr0, 1e-6),
                    "{} at {wl} m, RH {rh}: ({k}, {lr}), the script's ({k0}, {lr0})",
                    s.short_name
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 14 * 4 * 12);
}

#[test]
fn the_values_equal_a_raw_netcdf3_read_of_the_file() {
    // the reader's arrays against the netcdf3 crate's own read: the row-major order
    // (type, RH bin, wavelength) of ECMWF's files
    let table = AerosolOpticsTable::read(&fixture()).unwrap();
    let mut r = FileReader::open(fixture()).unwrap();
    let raw = |r: &mut FileReader, name: &str| -> Vec<f64> {
        match r.read_var(name).unwrap() {
            DataVector::F32(v) => v.into_iter().map(f64::from).collect(),
            _ => panic!("{name} not float32"),
        }
    };
    assert_eq!(
        table.mass_ext_hydrophilic,
        raw(&mut r, "mass_ext_mono_hydrophilic")
    );
    assert_eq!(
        table.lidar_ratio_hydrophobic,
        raw(&mut r, "lidar_ratio_mono_hydrophobic")
    );
    // sea salt bin 2 (hydrophilic 2) in RH bin 4 at 1064 nm: flat index (1·12 + 4)·4 + 3
    let ss2 = CamsSpecies::from_short_name("aermr02").unwrap();
    let (k, _) = table.optics(&ss2, 0.45, 1064e-9).unwrap();
    assert_eq!(
        k,
        raw(&mut r, "mass_ext_mono_hydrophilic")[(12 + 4) * 4 + 3]
    );
}

#[test]
fn the_rh_bin_is_ecrads_lower_bound_rule_at_the_edges() {
    let table = AerosolOpticsTable::read(&fixture()).unwrap();
    let lower = table.rh_lower.clone();
    // at a bin's lower bound exactly: the bin below (ecRad's rh > lower(k+1) to step up)
    for (k, &edge) in lower.iter().enumerate().skip(1) {
        assert_eq!(table.rh_bin(edge), k - 1, "RH = lower bound {}", edge);
        assert_eq!(table.rh_bin(edge.next_up()), k, "RH just above {}", edge);
    }
    assert_eq!(table.rh_bin(0.0), 0);
    assert_eq!(table.rh_bin(-0.3), 0);
    assert_eq!(table.rh_bin(1.0), 11);
    assert_eq!(table.rh_bin(1.7), 11);
    // the optics follow: sea salt bin 1 at RH = 0.85 exactly is bin 8 (0.8-0.85)
    let ss1 = CamsSpecies::from_short_name("aermr01").unwrap();
    let at_edge = table.optics(&ss1, lower[9], 532e-9).unwrap();
    assert_eq!(at_edge.0, philic(1, 8, 532e-9).0);
    let above = table.optics(&ss1, lower[9].next_up(), 532e-9).unwrap();
    assert_eq!(above.0, philic(1, 9, 532e-9).0);
    // hydrophobic types ignore RH
    let du = CamsSpecies::from_short_name("aermr06").unwrap();
    assert_eq!(
        table.optics(&du, 0.05, 355e-9).unwrap(),
        table.optics(&du, 0.99, 355e-9).unwrap()
    );
}

#[test]
fn relative_humidity_from_q_t_p_is_the_hand_value() {
    // q = 0.01, T = 293.15 K, p = 1000 hPa: e = 0.01·1e5/(0.622 + 0.378·0.01) = 1598.006 Pa;
    // e_s = 611.21·exp(17.502·19.99/260.96) = 2335.835 Pa; RH = 0.684126
    let rh = relative_humidity_over_water(0.01, 293.15, 1e5);
    assert!((rh - 0.684126).abs() < 1e-6, "{rh}");
    // clipped: supersaturated air is 1, negative q 0; NaN stays NaN
    assert_eq!(relative_humidity_over_water(0.05, 273.15, 1e5), 1.0);
    assert_eq!(relative_humidity_over_water(-1e-4, 273.15, 1e5), 0.0);
    assert!(relative_humidity_over_water(f64::NAN, 273.15, 1e5).is_nan());
}

#[test]
fn depolarization_defaults_by_species_and_wavelength() {
    let s = |n| CamsSpecies::from_short_name(n).unwrap();
    assert_eq!(particle_depolarization(&s("aermr05"), 532e-9), Some(0.31));
    assert_eq!(particle_depolarization(&s("aermr05"), 1064e-9), Some(0.27));
    assert_eq!(particle_depolarization(&s("aermr02"), 355e-9), Some(0.02));
    assert_eq!(particle_depolarization(&s("aermr09"), 532e-9), Some(0.05));
    assert_eq!(particle_depolarization(&s("aermr11"), 1064e-9), Some(0.0));
    assert_eq!(particle_depolarization(&s("aermr16"), 532e-9), Some(0.0));
    assert_eq!(particle_depolarization(&s("aermr05"), 865e-9), None);
}

/// Writes a copy of the fixture to `out` after `edit` changed its header or data.
fn damaged_copy(out: &Path, edit: impl FnOnce(&mut DataSet, &mut HashMap<String, DataVector>)) {
    let mut r = FileReader::open(fixture()).unwrap();
    let mut data = r.read_all_vars().unwrap();
    let (mut ds, version) = r.close();
    edit(&mut ds, &mut data);
    let mut w = FileWriter::open(out).unwrap();
    w.set_def(&ds, version, 0).unwrap();
    for name in ds.get_var_names() {
        match &data[&name] {
            DataVector::F32(v) => w.write_var_f32(&name, v).unwrap(),
            DataVector::U8(v) => w.write_var_u8(&name, v).unwrap(),
            DataVector::I8(v) => w.write_var_i8(&name, v).unwrap(),
            _ => panic!("{name}: unexpected type"),
        }
    }
    w.close().unwrap();
}

fn f32s<'a>(data: &'a mut HashMap<String, DataVector>, name: &str) -> &'a mut Vec<f32> {
    match data.get_mut(name).unwrap() {
        DataVector::F32(v) => v,
        _ => panic!("{name} not float32"),
    }
}

/// The one-line refusal of `path`, checked to name the file and `var`.
fn refusal_names(path: &Path, var: &str, reason: &str) -> String {
    let msg = AerosolOpticsTable::read(path).unwrap_err().to_string();
    assert!(!msg.contains('\n'), "not one line: {msg}");
    assert!(msg.contains(&path.display().to_string()), "no file: {msg}");
    assert!(
        msg.contains(&format!("`{var}`")),
        "no variable {var}: {msg}"
    );
    assert!(msg.contains(reason), "no `{reason}`: {msg}");
    msg
}

#[test]
fn a_missing_variable_is_refused_naming_file_and_variable() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("no_lidar_ratio.nc");
    damaged_copy(&p, |ds, data| {
        ds.remove_var("lidar_ratio_mono_hydrophilic").unwrap();
        data.remove("lidar_ratio_mono_hydrophilic");
    });
    refusal_names(&p, "lidar_ratio_mono_hydrophilic", "missing");
}

#[test]
fn a_nan_or_negative_value_is_refused_naming_file_and_variable() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nan.nc");
    damaged_copy(&p, |_, data| {
        f32s(data, "mass_ext_mono_hydrophobic")[17] = f32::NAN;
    });
    refusal_names(&p, "mass_ext_mono_hydrophobic", "NaN");
    let p = dir.path().join("negative.nc");
    damaged_copy(&p, |_, data| {
        f32s(data, "lidar_ratio_mono_hydrophilic")[5] = -3.0;
    });
    refusal_names(&p, "lidar_ratio_mono_hydrophilic", "-3");
}

#[test]
fn a_wrong_dimension_size_is_refused_naming_file_and_variable() {
    // relative_humidity2 one bound short of relative_humidity1: a new dimension of 11
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("short_rh2.nc");
    damaged_copy(&p, |ds, data| {
        ds.add_fixed_dim("rh_short", 11).unwrap();
        ds.remove_var("relative_humidity2").unwrap();
        ds.add_var_f32("relative_humidity2", &["rh_short"]).unwrap();
        f32s(data, "relative_humidity2").pop();
    });
    refusal_names(&p, "relative_humidity2", "11 bounds");
}

#[test]
fn a_wavelength_not_in_the_table_is_refused_naming_file_and_variable() {
    // the table's 532 nm moved to 530 nm: 532 nm is then refused, not interpolated
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("no_532.nc");
    damaged_copy(&p, |_, data| {
        f32s(data, "wavelength_mono")[1] = 530e-9;
    });
    let table = AerosolOpticsTable::read(&p).unwrap();
    let ss1 = CamsSpecies::from_short_name("aermr01").unwrap();
    let msg = table.optics(&ss1, 0.5, 532e-9).unwrap_err().to_string();
    assert!(!msg.contains('\n'), "{msg}");
    assert!(msg.contains(&p.display().to_string()), "{msg}");
    assert!(
        msg.contains("`wavelength_mono`") && msg.contains("no 532 nm"),
        "{msg}"
    );
    // wavelengths in nm instead of m: refused by their units
    let p = dir.path().join("nm.nc");
    damaged_copy(&p, |ds, _| {
        ds.get_var_mut("wavelength_mono")
            .unwrap()
            .remove_attr("units")
            .unwrap();
        ds.add_var_attr_string("wavelength_mono", "units", "nm")
            .unwrap();
    });
    refusal_names(&p, "wavelength_mono", "units \"nm\"");
}

#[test]
fn a_type_whose_code_is_not_the_species_is_refused() {
    // hydrophilic type 1 coded "DD": sea salt bin 1 refuses it
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("recoded.nc");
    damaged_copy(&p, |_, data| {
        match data.get_mut("code_hydrophilic").unwrap() {
            DataVector::U8(v) => v[..2].copy_from_slice(b"DD"),
            DataVector::I8(v) => v[..2].copy_from_slice(&[b'D' as i8, b'D' as i8]),
            _ => panic!("code_hydrophilic not char"),
        }
    });
    let table = AerosolOpticsTable::read(&p).unwrap();
    let ss1 = CamsSpecies::from_short_name("aermr01").unwrap();
    let msg = table.optics(&ss1, 0.5, 532e-9).unwrap_err().to_string();
    assert!(
        msg.contains("`code_hydrophilic`") && msg.contains("`DD`"),
        "{msg}"
    );
    // a species without optics (the SO2 precursor)
    let so2 = CamsSpecies::from_short_name("aermr12").unwrap();
    assert!(table.optics(&so2, 0.5, 532e-9).is_err());
}

#[test]
#[ignore = "needs ECMWF's own table: LIDARSIM_IFS_AEROSOL_TABLE=FILE cargo test --release \
            --test aerosol_optics_table -- --ignored"]
fn ecmwf_file_reads() {
    // ECMWF's own aerosol_ifs_rrtm_*.nc, if given: it reads, every mapped species has
    // finite positive optics at 355, 532 and 1064 nm in every RH bin, and the codes match
    let path = std::env::var_os("LIDARSIM_IFS_AEROSOL_TABLE")
        .expect("set LIDARSIM_IFS_AEROSOL_TABLE to ECMWF's aerosol_ifs_rrtm_*.nc");
    let table = AerosolOpticsTable::read(Path::new(&path)).unwrap();
    for s in CAMS_SPECIES.iter().filter(|s| s.ifs_type.is_some()) {
        for wl in [355e-9, 532e-9, 1064e-9] {
            for r in 0..table.rh_lower.len() {
                let rh = 0.5 * (table.rh_lower[r] + table.rh_upper[r]);
                let (k, lr) = table.optics(s, rh, wl).unwrap();
                assert!(k > 0.0 && lr > 0.0, "{} {wl} {rh}: {k} {lr}", s.short_name);
            }
        }
    }
}
