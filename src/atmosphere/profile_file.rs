//! User-supplied molecular profile (e.g. exported from MSIS or a radiosonde).
//!
//! # File format
//!
//! Plain text, one record per line:
//!
//! * `#` starts a comment, to the end of the line; blank lines are ignored.
//! * The first non-comment line is the **header**, naming the columns. It must
//!   name exactly one of two column sets, in any order:
//!   - `altitude_km pressure_hpa temperature_k` — N = p/(k_B·T), or
//!   - `altitude_km number_density_m3`.
//! * Every following non-comment line is a data row with one number per column.
//! * Fields are separated by whitespace and/or commas (so CSV works too).
//! * Altitudes (km, above mean sea level) must be finite and strictly
//!   increasing; pressures, temperatures and number densities must be finite
//!   and > 0. At least 2 rows.
//!
//! ```text
//! # radiosonde 2024-05-01 12 UTC
//! altitude_km, pressure_hpa, temperature_k
//! 0.0, 1013.25, 288.15
//! 1.0, 898.76, 281.65
//! ```
//!
//! Between rows the number density is interpolated linearly in ln N; below the
//! bottom row it is held at the bottom value. Above the top row this type gives 0;
//! the atmosphere (`Molecules`, in `molecules`) continues a profile that ends below 86 km
//! with the US Standard Atmosphere 1976, scaled to match at the top row, and says so
//! in the run's notes.

use std::path::Path;

use crate::config::{Checker, MolecularModel, ScenarioConfig};
use crate::constants::BOLTZMANN_J_PER_K;
use crate::error::{Error, Result};

/// Config key reported in parse errors.
const KEY: &str = "atmosphere.molecular.model.file";

/// A tabulated molecular number-density profile.
#[derive(Debug, Clone, PartialEq)]
pub struct MolecularProfile {
    /// Geometric altitudes, m, strictly increasing (at least 2).
    pub altitude_m: Vec<f64>,
    /// Number densities at those altitudes, m⁻³, all > 0.
    pub number_density_m3: Vec<f64>,
    /// Pressures at those altitudes, Pa, for a file that gives pressure and
    /// temperature (`None` for one that gives number densities).
    pub pressure_pa: Option<Vec<f64>>,
}

/// The two accepted column sets.
#[derive(Clone, Copy)]
enum Columns {
    /// Indices of altitude, pressure, temperature.
    PressureTemperature { z: usize, p: usize, t: usize },
    /// Indices of altitude, number density.
    NumberDensity { z: usize, n: usize },
}

const KNOWN_COLUMNS: [&str; 4] = [
    "altitude_km",
    "pressure_hpa",
    "temperature_k",
    "number_density_m3",
];

fn fields(line: &str) -> Vec<&str> {
    line.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|f| !f.is_empty())
        .collect()
}

fn parse_header(names: &[&str]) -> std::result::Result<Columns, String> {
    let mut index = [None; 4];
    for (col, name) in names.iter().enumerate() {
        match KNOWN_COLUMNS.iter().position(|k| k == name) {
            Some(k) if index[k].is_some() => {
                return Err(format!("column `{name}` appears twice in the header"));
            }
            Some(k) => index[k] = Some(col),
            None => {
                return Err(format!(
                    "unknown column `{name}` in the header; expected `altitude_km pressure_hpa temperature_k` \
                     or `altitude_km number_density_m3`"
                ));
            }
        }
    }
    match index {
        [Some(z), Some(p), Some(t), None] => Ok(Columns::PressureTemperature { z, p, t }),
        [Some(z), None, None, Some(n)] => Ok(Columns::NumberDensity { z, n }),
        _ => Err(format!(
            "header `{}` must name either `altitude_km pressure_hpa temperature_k` or \
             `altitude_km number_density_m3`",
            names.join(" ")
        )),
    }
}

/// Checks the molecular profiles a config gives as tables (`atmosphere.molecular.model`,
/// each segment's `molecular`) as a profile file's rows are checked, errors at their key.
pub fn validate_tables(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    let segments = config.scene.iter().flat_map(|s| s.segments.iter());
    let own = segments.enumerate().filter_map(|(i, seg)| {
        Some((
            format!("scene.segments[{i}].molecular"),
            seg.molecular.as_ref()?,
        ))
    });
    let base = (
        "atmosphere.molecular.model".to_string(),
        &config.atmosphere.molecular.model,
    );
    for (key, model) in std::iter::once(base).chain(own) {
        if let MolecularModel::Table {
            altitude_km,
            pressure_hpa,
            temperature_k,
        } = model
        {
            match MolecularProfile::from_table(altitude_km, pressure_hpa, temperature_k, "") {
                Err(Error::Config { reason, .. }) => return Err(c.fail(&key, reason)),
                other => other.map(drop)?,
            }
        }
    }
    Ok(())
}

impl MolecularProfile {
    /// Reads and parses a profile file (format in the module docs). Parse errors
    /// are [`Error::Config`] naming the file, the key and the line; a file that is
    /// missing, unreadable or not a regular file (a FIFO is refused before it is opened,
    /// [`crate::input_file`]) names the key and the path.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = crate::input_file::read_to_string(KEY, path)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses profile text; `source_name` names it in errors (usually the path).
    pub fn parse(text: &str, source_name: &str) -> Result<Self> {
        let fail = |line: usize, reason: String| {
            Error::config(source_name, KEY, format!("line {line}: {reason}"))
        };
        let mut columns: Option<(Columns, usize)> = None;
        let mut altitude_m = Vec::new();
        let mut number_density_m3 = Vec::new();
        let mut pressure_pa = Vec::new();
        for (k, raw) in text.lines().enumerate() {
            let line_no = k + 1;
            let content = raw.split('#').next().unwrap_or("");
            let f = fields(content);
            if f.is_empty() {
                continue;
            }
            let Some((cols, width)) = columns else {
                if f[0].parse::<f64>().is_ok() {
                    return Err(fail(
                        line_no,
                        "found numbers before the header line; the first non-comment line must name the columns \
                         (`altitude_km pressure_hpa temperature_k` or `altitude_km number_density_m3`)"
                            .into(),
                    ));
                }
                columns = Some((parse_header(&f).map_err(|r| fail(line_no, r))?, f.len()));
                continue;
            };
            if f.len() != width {
                return Err(fail(
                    line_no,
                    format!("expected {width} values, found {}", f.len()),
                ));
            }
            let value = |col: usize, name: &str| -> Result<f64> {
                let v: f64 = f[col]
                    .parse()
                    .map_err(|_| fail(line_no, format!("{name} `{}` is not a number", f[col])))?;
                if !v.is_finite() {
                    return Err(fail(line_no, format!("{name} `{}` is not finite", f[col])));
                }
                Ok(v)
            };
            let positive = |col: usize, name: &str| -> Result<f64> {
                let v = value(col, name)?;
                if v <= 0.0 {
                    return Err(fail(line_no, format!("{name} must be > 0, found {v}")));
                }
                Ok(v)
            };
            let (z_km, n) = match cols {
                Columns::PressureTemperature { z, p, t } => {
                    let z_km = value(z, "altitude_km")?;
                    let p_hpa = positive(p, "pressure_hpa")?;
                    let t_k = positive(t, "temperature_k")?;
                    pressure_pa.push(p_hpa * 100.0);
                    (z_km, p_hpa * 100.0 / (BOLTZMANN_J_PER_K * t_k))
                }
                Columns::NumberDensity { z, n } => {
                    (value(z, "altitude_km")?, positive(n, "number_density_m3")?)
                }
            };
            let z_m = z_km * 1000.0;
            if let Some(&prev) = altitude_m.last()
                && z_m <= prev
            {
                return Err(fail(
                    line_no,
                    format!(
                        "altitude {z_km} km is not above the previous row's {} km",
                        prev / 1000.0
                    ),
                ));
            }
            altitude_m.push(z_m);
            number_density_m3.push(n);
        }
        let last_line = text.lines().count().max(1);
        if columns.is_none() {
            return Err(fail(
                last_line,
                "no header line: expected `altitude_km pressure_hpa temperature_k` or `altitude_km number_density_m3`"
                    .into(),
            ));
        }
        if altitude_m.len() < 2 {
            return Err(fail(
                last_line,
                format!("need at least 2 data rows, found {}", altitude_m.len()),
            ));
        }
        Ok(Self {
            altitude_m,
            number_density_m3,
            pressure_pa: (!pressure_pa.is_empty()).then_some(pressure_pa),
        })
    }

    /// The profile of a config's table (`atmosphere.molecular.model = { altitude_km,
    /// pressure_hpa, temperature_k }`, or a model column's): the rows of a profile file of
    /// pressures and temperatures, checked as [`parse`](Self::parse) checks them; errors
    /// name `source_name`, the key `atmosphere.molecular.model` and the row.
    pub fn from_table(
        altitude_km: &[f64],
        pressure_hpa: &[f64],
        temperature_k: &[f64],
        source_name: &str,
    ) -> Result<Self> {
        let fail =
            |reason: String| Error::config(source_name, "atmosphere.molecular.model", reason);
        if altitude_km.len() != pressure_hpa.len() || altitude_km.len() != temperature_k.len() {
            return Err(fail(format!(
                "altitude_km, pressure_hpa and temperature_k must be as long: {}, {} and {}",
                altitude_km.len(),
                pressure_hpa.len(),
                temperature_k.len()
            )));
        }
        if altitude_km.len() < 2 {
            return Err(fail(format!(
                "need at least 2 rows, found {}",
                altitude_km.len()
            )));
        }
        let mut text = String::from("altitude_km pressure_hpa temperature_k\n");
        for ((z, p), t) in altitude_km.iter().zip(pressure_hpa).zip(temperature_k) {
            // round-trip formatting: the parse below reads back exactly these values
            text.push_str(&format!("{z:e} {p:e} {t:e}\n"));
        }
        // one rule for every check: the file's, each row numbered after the header
        Self::parse(&text, source_name).map_err(|e| match e {
            Error::Config { reason, .. } => {
                // "line N: why" of the text above is index N − 2 of the arrays (line 1 is
                // the header)
                let row = reason
                    .strip_prefix("line ")
                    .and_then(|r| r.split_once(": "))
                    .and_then(|(n, why)| Some((n.parse::<usize>().ok()?.checked_sub(2)?, why)));
                match row {
                    Some((k, why)) => fail(format!("index {k}: {why}")),
                    None => fail(reason),
                }
            }
            e => e,
        })
    }

    /// Number density, m⁻³, at geometric altitude `altitude_m`: log-linear
    /// between rows, 0 above the top row, the bottom value below the bottom
    /// row; NaN for NaN.
    pub fn number_density_m3(&self, altitude_m: f64) -> f64 {
        self.log_linear(&self.number_density_m3, altitude_m)
    }

    /// Pressure, Pa, at geometric altitude `altitude_m`, interpolated as the number
    /// density is (log-linear; 0 above the top row); `None` for a file without
    /// pressures. The temperature that goes with it is `p/(k_B·N)` (the ideal-gas law
    /// the rows satisfy), so that the three agree between rows too.
    pub fn pressure_pa(&self, altitude_m: f64) -> Option<f64> {
        let p = self.pressure_pa.as_ref()?;
        Some(self.log_linear(p, altitude_m))
    }

    /// `values` (one per row, all > 0) at `altitude_m`: log-linear between rows, 0
    /// above the top row, the bottom value below the bottom row; NaN for NaN.
    fn log_linear(&self, values: &[f64], altitude_m: f64) -> f64 {
        let z = &self.altitude_m;
        let n = values;
        if altitude_m.is_nan() {
            return f64::NAN;
        }
        let last = z.len() - 1;
        if altitude_m > z[last] {
            return 0.0;
        }
        if altitude_m == z[last] {
            return n[last];
        }
        if altitude_m <= z[0] {
            return n[0];
        }
        // z[i] ≤ altitude < z[i+1]
        let i = z.partition_point(|&zi| zi <= altitude_m) - 1;
        if altitude_m == z[i] {
            return n[i];
        }
        let f = (altitude_m - z[i]) / (z[i + 1] - z[i]);
        (n[i].ln() + f * (n[i + 1].ln() - n[i].ln())).exp()
    }

    /// Altitude of the top row, m.
    pub fn top_altitude_m(&self) -> f64 {
        self.altitude_m[self.altitude_m.len() - 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::us76;

    const EXAMPLE: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/configs/atmospheres/us76_1km.txt"
    ));

    fn err(text: &str) -> String {
        match MolecularProfile::parse(text, "test.txt") {
            Ok(p) => panic!("parsed: {p:?}"),
            Err(e) => e.to_string(),
        }
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    /// Writes the example file from the us76 module:
    /// `ATMOS_WRITE_EXAMPLE=1 cargo test write_us76_example -- --ignored`.
    #[test]
    #[ignore]
    fn write_us76_example() {
        let mut s = String::from(
            "# U.S. Standard Atmosphere 1976, 0-86 km geometric altitude at 1 km steps,\n\
             # generated by lidarsim's atmosphere::us76 (NOAA-S/T 76-1562 definition).\n\
             #\n\
             # Format of a molecular profile file (atmosphere.molecular.model = { file = \"...\" }):\n\
             #  - '#' starts a comment; blank lines are ignored.\n\
             #  - The first other line is the header naming the columns, either\n\
             #      altitude_km pressure_hpa temperature_k    (N = p / (k_B T))\n\
             #    or\n\
             #      altitude_km number_density_m3\n\
             #    in any order.\n\
             #  - Then one row per altitude; fields separated by spaces, tabs and/or commas.\n\
             #  - Altitudes (km above sea level) strictly increasing; pressure, temperature\n\
             #    and number density finite and > 0; at least 2 rows.\n\
             #  - Between rows N is interpolated linearly in ln N; above the top row N = 0;\n\
             #    below the bottom row N is held at the bottom value.\n\
             #\n\
             altitude_km  pressure_hpa  temperature_k\n",
        );
        for k in 0..=86 {
            let st = us76::state(k as f64 * 1000.0).unwrap();
            s.push_str(&format!(
                "{:>5.1}  {:>13.6e}  {:>9.3}\n",
                k as f64,
                st.pressure_pa / 100.0,
                st.temperature_k
            ));
        }
        if std::env::var_os("ATMOS_WRITE_EXAMPLE").is_some() {
            let path = concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/configs/atmospheres/us76_1km.txt"
            );
            std::fs::write(path, s).unwrap();
        } else {
            print!("{s}");
        }
    }

    #[test]
    fn example_file_reproduces_us76() {
        let p = MolecularProfile::parse(EXAMPLE, "us76_1km.txt").unwrap();
        assert_eq!(p.altitude_m.len(), 87);
        assert_eq!(p.top_altitude_m(), 86_000.0);
        for (&z, &n) in p.altitude_m.iter().zip(&p.number_density_m3) {
            assert!(rel(n, us76::number_density_m3(z)) < 1e-4, "at {z} m");
            assert!(rel(p.number_density_m3(z), us76::number_density_m3(z)) < 0.01);
        }
        // Between grid points log-linear interpolation stays within 1 % of US76.
        for k in 0..860 {
            let z = k as f64 * 100.0 + 50.0;
            assert!(
                rel(p.number_density_m3(z), us76::number_density_m3(z)) < 0.01,
                "at {z} m"
            );
        }
    }

    #[test]
    fn number_density_form_csv_and_comments() {
        let text = "# sonde\n\n  number_density_m3 , altitude_km  # reordered\n2.5e25, 0\n1.0e25,8 # inline\n";
        let p = MolecularProfile::parse(text, "t").unwrap();
        assert_eq!(p.altitude_m, vec![0.0, 8000.0]);
        assert_eq!(p.number_density_m3, vec![2.5e25, 1.0e25]);
        // Geometric mean halfway, 0 above, clamp below.
        assert!(rel(p.number_density_m3(4000.0), (2.5e25_f64 * 1.0e25).sqrt()) < 1e-12);
        assert_eq!(p.number_density_m3(8000.0), 1.0e25);
        assert_eq!(p.number_density_m3(8000.1), 0.0);
        assert_eq!(p.number_density_m3(-300.0), 2.5e25);
        assert_eq!(p.top_altitude_m(), 8000.0);
    }

    #[test]
    fn pressure_temperature_form() {
        let p = MolecularProfile::parse(
            "altitude_km pressure_hpa temperature_k\n0 1013.25 288.15\n1 898.76 281.65\n",
            "t",
        )
        .unwrap();
        assert!(rel(p.number_density_m3[0], 2.5469e25) < 1e-4);
        // Negative altitudes are allowed (below sea level).
        assert!(
            MolecularProfile::parse(
                "altitude_km number_density_m3\n-0.4 2.6e25\n0 2.5e25\n",
                "t"
            )
            .is_ok()
        );
    }

    #[test]
    fn error_names_file_key_and_line() {
        let e = err("altitude_km number_density_m3\n0 2.5e25\n1 abc\n");
        assert_eq!(
            e,
            "test.txt: key `atmosphere.molecular.model.file`: line 3: number_density_m3 `abc` is not a number"
        );
    }

    #[test]
    fn missing_header() {
        assert!(
            err("# only comment\n0 1013 288\n1 900 281\n")
                .contains("line 2: found numbers before the header")
        );
        assert!(err("").contains("no header line"));
        assert!(err("# nothing\n\n").contains("line 2: no header line"));
    }

    #[test]
    fn unknown_or_incomplete_columns() {
        assert!(
            err("altitude_km pressure_pa temperature_k\n")
                .contains("line 1: unknown column `pressure_pa`")
        );
        assert!(err("altitude_km pressure_hpa\n0 1013\n1 900\n").contains("must name either"));
        assert!(
            err("altitude_km pressure_hpa temperature_k number_density_m3\n")
                .contains("must name either")
        );
        assert!(err("altitude_km altitude_km number_density_m3\n").contains("appears twice"));
    }

    #[test]
    fn non_numeric_and_wrong_width() {
        assert!(
            err("altitude_km number_density_m3\n0 2.5e25\n1km 2.3e25\n")
                .contains("line 3: altitude_km `1km` is not a number")
        );
        assert!(
            err("altitude_km number_density_m3\n0 2.5e25 7\n1 2e25\n")
                .contains("line 2: expected 2 values, found 3")
        );
        assert!(
            err("altitude_km number_density_m3\n0\n")
                .contains("line 2: expected 2 values, found 1")
        );
    }

    #[test]
    fn negative_or_zero_values() {
        assert!(
            err("altitude_km pressure_hpa temperature_k\n0 -1013 288\n1 900 281\n")
                .contains("line 2: pressure_hpa must be > 0, found -1013")
        );
        assert!(
            err("altitude_km pressure_hpa temperature_k\n0 1013 288\n1 900 0\n")
                .contains("line 3: temperature_k must be > 0")
        );
        assert!(
            err("altitude_km number_density_m3\n0 -2.5e25\n1 2e25\n")
                .contains("number_density_m3 must be > 0")
        );
    }

    #[test]
    fn non_increasing_altitude() {
        assert!(
            err("altitude_km number_density_m3\n0 2.5e25\n1 2.3e25\n1 2.2e25\n")
                .contains("line 4: altitude 1 km is not above the previous row's 1 km")
        );
        assert!(
            err("altitude_km number_density_m3\n0 2.5e25\n2 2.3e25\n1 2.4e25\n")
                .contains("line 4:")
        );
    }

    #[test]
    fn nan_and_infinity() {
        assert!(
            err("altitude_km number_density_m3\n0 NaN\n1 2e25\n")
                .contains("line 2: number_density_m3 `NaN` is not finite")
        );
        assert!(
            err("altitude_km number_density_m3\n0 2.5e25\nnan 2e25\n")
                .contains("line 3: altitude_km `nan` is not finite")
        );
        assert!(
            err("altitude_km pressure_hpa temperature_k\n0 inf 288\n1 900 281\n")
                .contains("not finite")
        );
    }

    #[test]
    fn fewer_than_two_rows() {
        assert!(
            err("altitude_km number_density_m3\n0 2.5e25\n")
                .contains("line 2: need at least 2 data rows, found 1")
        );
        assert!(err("altitude_km number_density_m3\n").contains("found 0"));
    }

    #[test]
    fn from_file_reads_and_reports_io_errors() {
        let dir = std::env::temp_dir().join(format!("atmos-profile-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.txt");
        std::fs::write(&good, "altitude_km number_density_m3\n0 2.5e25\n1 2.3e25\n").unwrap();
        assert_eq!(
            MolecularProfile::from_file(&good).unwrap().altitude_m.len(),
            2
        );
        let bad = dir.join("bad.txt");
        std::fs::write(&bad, "altitude_km number_density_m3\n0 2.5e25\n").unwrap();
        let e = MolecularProfile::from_file(&bad).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}: key `atmosphere.molecular.model.file`: line 2:",
                bad.display()
            )),
            "{e}"
        );
        let missing = dir.join("missing.txt");
        let e = MolecularProfile::from_file(&missing)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            format!(
                "atmosphere.molecular.model.file {}: no such file or directory",
                missing.display()
            )
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
