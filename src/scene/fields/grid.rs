//! The fields' grid: latitude, longitude and time axes, CF time units, and the stated
//! sampling rule — the weights of the grid points and times a profile's value is made
//! of: bilinear in latitude and longitude at each of the two times around it, then
//! linear in time (`linear`), or the nearest point and time (`nearest`, ties to the
//! lower index).

use crate::config::FieldsInterpolation;

/// The horizontal and time axes of the fields.
#[derive(Debug, Clone)]
pub struct Axes {
    /// Latitudes, degrees north, strictly monotonic (either way).
    pub lat: Vec<f64>,
    /// Longitudes, degrees east, strictly increasing.
    pub lon: Vec<f64>,
    /// Times, Unix seconds, strictly increasing.
    pub time_s: Vec<f64>,
}

/// One grid point and time of a sample and its weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weight {
    /// Time index.
    pub t: usize,
    /// Latitude index.
    pub y: usize,
    /// Longitude index.
    pub x: usize,
    /// Weight (the weights of a sample sum to 1).
    pub w: f64,
}

/// `x` between two values of the strictly monotonic `axis`: `(i0, i1, w1)` with the
/// value `(1 − w1)·v[i0] + w1·v[i1]`; `None` outside the axis.
pub fn bracket(axis: &[f64], x: f64) -> Option<(usize, usize, f64)> {
    let n = axis.len();
    if n == 1 {
        return (x == axis[0]).then_some((0, 0, 0.0));
    }
    let rising = axis[1] > axis[0];
    let (lo, hi) = if rising {
        (axis[0], axis[n - 1])
    } else {
        (axis[n - 1], axis[0])
    };
    if !(lo..=hi).contains(&x) {
        return None;
    }
    // the last index whose value is at or before x (in the axis's direction)
    let before = |v: f64| if rising { v <= x } else { v >= x };
    let i = axis.partition_point(|&v| before(v)).clamp(1, n - 1) - 1;
    let w = (x - axis[i]) / (axis[i + 1] - axis[i]);
    Some((i, i + 1, w))
}

impl Axes {
    /// Whether the longitudes go round the globe (n·Δλ = 360° within 1e-6°).
    pub fn global(&self) -> bool {
        let n = self.lon.len();
        n > 1 && ((self.lon[1] - self.lon[0]) * n as f64 - 360.0).abs() < 1e-6
    }

    /// `lon` in the grid's convention: shifted by 360° into [λ0, λ0 + 360).
    fn longitude(&self, lon: f64) -> f64 {
        self.lon[0] + (lon - self.lon[0]).rem_euclid(360.0)
    }

    /// The longitude bracket, across the seam of a global grid.
    fn lon_bracket(&self, lon: f64) -> Option<(usize, usize, f64)> {
        let x = self.longitude(lon);
        let n = self.lon.len();
        match bracket(&self.lon, x) {
            Some(b) => Some(b),
            None if self.global() => {
                let dx = self.lon[1] - self.lon[0];
                Some((n - 1, 0, (x - self.lon[n - 1]) / dx))
            }
            None => None,
        }
    }

    /// The weights of the sample at Unix time `t_s`, latitude `lat`, longitude `lon`,
    /// or which axis it falls outside.
    pub fn weights(
        &self,
        rule: FieldsInterpolation,
        t_s: f64,
        lat: f64,
        lon: f64,
    ) -> Result<Vec<Weight>, &'static str> {
        let t = bracket(&self.time_s, t_s).ok_or("time")?;
        let y = bracket(&self.lat, lat).ok_or("latitude")?;
        let x = self.lon_bracket(lon).ok_or("longitude")?;
        let pairs = |(i0, i1, w1): (usize, usize, f64)| match rule {
            FieldsInterpolation::Linear => [(i0, 1.0 - w1), (i1, w1)],
            FieldsInterpolation::Nearest if w1 > 0.5 => [(i1, 1.0), (i0, 0.0)],
            FieldsInterpolation::Nearest => [(i0, 1.0), (i1, 0.0)],
        };
        let mut out = Vec::with_capacity(8);
        for (it, wt) in pairs(t) {
            for (iy, wy) in pairs(y) {
                for (ix, wx) in pairs(x) {
                    let w = wt * wy * wx;
                    if w != 0.0 {
                        out.push(Weight {
                            t: it,
                            y: iy,
                            x: ix,
                            w,
                        });
                    }
                }
            }
        }
        Ok(out)
    }
}

/// Seconds per unit of a CF time unit.
fn unit_seconds(unit: &str) -> Option<f64> {
    Some(match unit {
        "seconds" | "second" | "secs" | "s" => 1.0,
        "minutes" | "minute" | "mins" | "min" => 60.0,
        "hours" | "hour" | "hrs" | "h" => 3600.0,
        "days" | "day" | "d" => 86400.0,
        _ => return None,
    })
}

/// Days from 1970-01-01 to the proleptic Gregorian date `y-m-d` (civil calendar
/// arithmetic on 400-year eras).
pub fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = if y >= 0 { y } else { y - 399 } / 400;
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// CF time units `"UNIT since YYYY-MM-DD[ HH:MM[:SS[.f]]][Z| UTC|+00:00]"` (Gregorian,
/// UTC): `(seconds per unit, Unix seconds of the origin)`.
pub fn parse_time_units(units: &str) -> Result<(f64, f64), String> {
    let bad = || format!("time units {units:?} are not \"UNIT since YYYY-MM-DD hh:mm:ss\" (UTC)");
    let (unit, origin) = units.trim().split_once(" since ").ok_or_else(bad)?;
    let per = unit_seconds(unit.trim()).ok_or_else(bad)?;
    let mut o = origin.trim().replace('T', " ");
    for tail in [" UTC", "Z", "+00:00", " +00:00", "+0000", " 00:00"] {
        if o.len() > 10
            && let Some(s) = o.strip_suffix(tail)
        {
            o = s.trim_end().to_string();
        }
    }
    let (date, clock) = o.split_once(' ').unwrap_or((&o, "00:00:00"));
    let num = |s: &str| s.parse::<i64>().map_err(|_| bad());
    let d: Vec<&str> = date.split('-').collect();
    if d.len() != 3 {
        return Err(bad());
    }
    let (y, m, day) = (num(d[0])?, num(d[1])?, num(d[2])?);
    if !(1..=12).contains(&m) || !(1..=31).contains(&day) {
        return Err(bad());
    }
    let c: Vec<&str> = clock.split(':').collect();
    if c.len() < 2 || c.len() > 3 {
        return Err(bad());
    }
    let (hh, mm) = (num(c[0])?, num(c[1])?);
    let ss: f64 = match c.get(2) {
        Some(s) => s.parse().map_err(|_| bad())?,
        None => 0.0,
    };
    let origin_s = days_from_civil(y, m, day) as f64 * 86400.0 + (hh * 3600 + mm * 60) as f64 + ss;
    Ok((per, origin_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cf_time_units_from_1900() {
        // 1900-01-01 is 25,567 days before 1970-01-01 (70 years, 17 leap days)
        let (per, o) = parse_time_units("hours since 1900-01-01 00:00:00.0").unwrap();
        assert_eq!((per, o), (3600.0, -25_567.0 * 86400.0));
        let (_, o) = parse_time_units("seconds since 2024-03-01T06:30:00Z").unwrap();
        assert_eq!(o, 1_709_274_600.0);
        assert!(parse_time_units("hours since noon").is_err());
    }

    #[test]
    fn bilinear_weights_sum_to_one_and_nearest_picks_one() {
        let a = Axes {
            lat: vec![50.0, 49.0, 48.0],
            lon: vec![0.0, 1.0, 2.0],
            time_s: vec![0.0, 3600.0],
        };
        let w = a
            .weights(FieldsInterpolation::Linear, 900.0, 48.5, 1.25)
            .unwrap();
        assert_eq!(w.len(), 8);
        assert!((w.iter().map(|w| w.w).sum::<f64>() - 1.0).abs() < 1e-15);
        let n = a
            .weights(FieldsInterpolation::Nearest, 900.0, 48.4, 1.75)
            .unwrap();
        assert_eq!(
            n,
            [Weight {
                t: 0,
                y: 2,
                x: 2,
                w: 1.0
            }]
        );
        assert_eq!(
            a.weights(FieldsInterpolation::Linear, 0.0, 47.0, 1.0),
            Err("latitude")
        );
        assert_eq!(
            a.weights(FieldsInterpolation::Linear, 4000.0, 48.0, 1.0),
            Err("time")
        );
    }
}
