//! An independent single-scattering computation of the daylight sky a nadir view sees
//! from space, for `tests/solar_background.rs` and `validation/daylight_sky.rs`
//! (report: validation/reports/daylight_sky.md). It calls nothing of lidarsim's sky
//! code: it builds its own molecular column (U.S. Standard Atmosphere 1976 below 86 km
//! from its defining layer table, hydrostatic, times Bucholtz's 1995 Rayleigh
//! cross-section), takes the particles as a list of extinction profiles with their
//! Henyey–Greenstein asymmetry, and integrates on a fine grid (10 m below 5 km, 50 m
//! above) by the midpoint rule:
//!
//! - the sun's slant optical depth from every grid point through the spherical shells
//!   above it, exactly (straight ray, no refraction), the partial shell included;
//! - the path radiance `F/(4π)·Σ_k σ_k·P(Θ)·e^{−S_k−V_k}·Δz`, Θ = 180° − θ_s;
//! - the once-scattered diffuse irradiance at the ground,
//!   `F·Σ_k e^{−S_k}·Δz·σ_k·(1/4π)∫↓ P(Θ') e^{−τ_k/μ'} dΩ'` with a 96 × 144 midpoint
//!   rule in (μ', φ');
//! - the reflected light's way up, direct `e^{−V_0}` plus the light the air scatters
//!   once into the view, computed directly (not by reciprocity) with the same rule.
//!
//! `L = ρ/π·(F·μ_s·e^{−S_0} + E_d)·T↑ + L_path`.

use std::f64::consts::PI;

/// Earth radius used for the spherical shells, m (mean radius).
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// Bucholtz (1995, Appl. Opt. 34, 2765) Eq. 8 with his Table 3 coefficients for
/// λ > 0.5 µm: Rayleigh cross-section, m² (5.16e-31 at 532 nm).
pub fn bucholtz_cross_section_m2(wavelength_um: f64) -> f64 {
    let (a, b, c, d) = (4.01061e-28, 3.99668, 1.10298e-3, 2.71393e-2);
    a * wavelength_um.powf(-(b + c * wavelength_um + d / wavelength_um)) * 1e-4
}

/// U.S. Standard Atmosphere 1976 number density below 86 km, m⁻³, from its defining
/// table (geopotential base heights, lapse rates, base pressures), hydrostatic.
pub fn us76_number_density_m3(z_m: f64) -> f64 {
    const H_KM: [f64; 8] = [0.0, 11.0, 20.0, 32.0, 47.0, 51.0, 71.0, 84.852];
    const LAPSE_K_PER_KM: [f64; 7] = [-6.5, 0.0, 1.0, 2.8, 0.0, -2.8, -2.0];
    const T_K: [f64; 7] = [288.15, 216.65, 216.65, 228.65, 270.65, 270.65, 214.65];
    const P_PA: [f64; 7] = [
        101_325.0, 22_632.06, 5_474.889, 868.0187, 110.9063, 66.938_87, 3.956_420,
    ];
    const G0_M_OVER_R: f64 = 34.163_195; // K/km: g0·M0/R*
    const R0_KM: f64 = 6_356.766;
    let z_km = z_m / 1e3;
    if !(0.0..86.0).contains(&z_km) {
        return 0.0;
    }
    let h = R0_KM * z_km / (R0_KM + z_km);
    let b = (0..7).rev().find(|&b| h >= H_KM[b]).unwrap_or(0);
    let (l, tb, pb) = (LAPSE_K_PER_KM[b], T_K[b], P_PA[b]);
    let t = tb + l * (h - H_KM[b]);
    let p = if l == 0.0 {
        pb * (-G0_M_OVER_R * (h - H_KM[b]) / tb).exp()
    } else {
        pb * (tb / t).powf(G0_M_OVER_R / l)
    };
    p / (1.380_649e-23 * t)
}

/// Henyey–Greenstein phase function (4π-normalized).
fn hg(cos_theta: f64, g: f64) -> f64 {
    (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta).powf(1.5)
}

/// Rayleigh phase function (4π-normalized).
fn rayleigh(cos_theta: f64) -> f64 {
    0.75 * (1.0 + cos_theta * cos_theta)
}

/// The column: molecules (scattering), an absorber, particle species with their g.
pub struct Column {
    /// Grid cell edges, m (from the reflector up).
    edges: Vec<f64>,
    /// Per cell: molecular extinction, absorber extinction, m⁻¹.
    mol: Vec<f64>,
    abs: Vec<f64>,
    /// Per species: g and per-cell extinction, m⁻¹.
    species: Vec<(f64, Vec<f64>)>,
}

/// One sky: its reflected and path parts, photons m⁻² s⁻¹ sr⁻¹ nm⁻¹ (per unit F if F = 1).
#[derive(Debug, Clone, Copy)]
pub struct Sky {
    /// Reflected sunlight reaching the view.
    pub reflected: f64,
    /// Path radiance.
    pub path: f64,
}

impl Column {
    /// US76 molecules at `wavelength_um` (×`molecular_scale`) from `reflector_m` to
    /// 86 km, with `absorber(z)` m⁻¹ and particle species `(g, extinction(z) m⁻¹)`.
    pub fn new(
        wavelength_um: f64,
        reflector_m: f64,
        absorber: &dyn Fn(f64) -> f64,
        species: &[(f64, &dyn Fn(f64) -> f64)],
    ) -> Column {
        let mut edges = vec![reflector_m];
        let mut z = reflector_m;
        while z < 86_000.0 {
            z = (z + if z < 5_000.0 { 10.0 } else { 50.0 }).min(86_000.0);
            edges.push(z);
        }
        let mid: Vec<f64> = edges.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let sigma = bucholtz_cross_section_m2(wavelength_um);
        Column {
            mol: mid
                .iter()
                .map(|&z| sigma * us76_number_density_m3(z))
                .collect(),
            abs: mid.iter().map(|&z| absorber(z)).collect(),
            species: species
                .iter()
                .map(|(g, f)| (*g, mid.iter().map(|&z| f(z)).collect()))
                .collect(),
            edges,
        }
    }

    fn n(&self) -> usize {
        self.mol.len()
    }

    fn ext(&self, k: usize) -> f64 {
        self.mol[k] + self.abs[k] + self.species.iter().map(|s| s.1[k]).sum::<f64>()
    }

    /// Vertical molecular (Rayleigh) optical depth of the column.
    pub fn molecular_depth(&self) -> f64 {
        (0..self.n())
            .map(|k| self.mol[k] * (self.edges[k + 1] - self.edges[k]))
            .sum()
    }

    /// Slant optical depth from the midpoint of cell k to the top at `sin_z`, with the
    /// extinction `e(j)` per cell.
    fn slant(&self, k: usize, sin_z: f64, e: &dyn Fn(usize) -> f64) -> f64 {
        let r0 = EARTH_RADIUS_M + 0.5 * (self.edges[k] + self.edges[k + 1]);
        let p2 = (r0 * sin_z).powi(2);
        let l = |z: f64| {
            let r = EARTH_RADIUS_M + z;
            (r * r - p2).max(0.0).sqrt()
        };
        let mut s = e(k) * (l(self.edges[k + 1]) - r0 * (1.0 - sin_z * sin_z).sqrt());
        for j in k + 1..self.n() {
            s += e(j) * (l(self.edges[j + 1]) - l(self.edges[j]));
        }
        s
    }

    /// The molecular air mass from the reflector (its lowest cell) at `zenith_deg`.
    pub fn molecular_air_mass(&self, zenith_deg: f64) -> f64 {
        let sin_z = zenith_deg.to_radians().sin();
        let mut slant = self.slant(0, sin_z, &|j| self.mol[j]);
        // from the reflector itself: add the lowest half cell's chord
        let dz = 0.5 * (self.edges[1] - self.edges[0]);
        slant += self.mol[0] * dz / zenith_deg.to_radians().cos();
        slant / self.molecular_depth()
    }

    /// Per species (molecules first) the downward hemisphere's kernel for a beam of
    /// direction (sin, −mu): for each μ' node, Σ_φ P·ΔΩ/(4π).
    fn kernels(&self, mu: f64, nodes_mu: usize, nodes_phi: usize) -> Vec<Vec<f64>> {
        let sin_b = (1.0 - mu * mu).max(0.0).sqrt();
        let d_mu = 1.0 / nodes_mu as f64;
        let d_phi = 2.0 * PI / nodes_phi as f64;
        let mut out = vec![vec![0.0; nodes_mu]; 1 + self.species.len()];
        for j in 0..nodes_mu {
            let m = (j as f64 + 0.5) * d_mu;
            let s = (1.0 - m * m).sqrt();
            for q in 0..nodes_phi {
                let c = mu * m + sin_b * s * ((q as f64 + 0.5) * d_phi).cos();
                let w = d_mu * d_phi / (4.0 * PI);
                out[0][j] += w * rayleigh(c);
                for (o, (g, _)) in out[1..].iter_mut().zip(&self.species) {
                    o[j] += w * hg(c, *g);
                }
            }
        }
        out
    }

    /// Once-scattered diffuse light reaching the reflector (per unit F) from a beam of
    /// direction cosine `mu` whose depth to the top from cell k is `depth[k]`, each cell
    /// seen from the reflector through its vertical depth `below[k]` at slant 1/μ'.
    fn diffuse(&self, mu: f64, depth: &[f64], below: &[f64]) -> f64 {
        let (nm, np) = (96, 144);
        let kern = self.kernels(mu, nm, np);
        let mus: Vec<f64> = (0..nm).map(|j| (j as f64 + 0.5) / nm as f64).collect();
        let mut e = 0.0;
        for k in 0..self.n() {
            let dz = self.edges[k + 1] - self.edges[k];
            let mut h = 0.0;
            for (j, m) in mus.iter().enumerate() {
                let a = (-below[k] / m).exp();
                let mut p = self.mol[k] * kern[0][j];
                for (s, kk) in self.species.iter().zip(&kern[1..]) {
                    p += s.1[k] * kk[j];
                }
                h += a * p;
            }
            e += (-depth[k]).exp() * dz * h;
        }
        e
    }

    /// The sky at `zenith_deg` over albedo `albedo` under F = `irradiance`.
    pub fn sky(&self, albedo: f64, irradiance: f64, zenith_deg: f64) -> Sky {
        let n = self.n();
        let (sin_z, mu_s) = zenith_deg.to_radians().sin_cos();
        let ext = |j: usize| self.ext(j);
        let dz = |k: usize| self.edges[k + 1] - self.edges[k];
        // vertical depth from each cell's midpoint to the top and to the reflector
        let mut top = vec![0.0; n];
        let mut acc = 0.0;
        for k in (0..n).rev() {
            top[k] = acc + 0.5 * ext(k) * dz(k);
            acc += ext(k) * dz(k);
        }
        let total = acc;
        let below: Vec<f64> = top.iter().map(|t| total - t).collect();
        let sun: Vec<f64> = (0..n).map(|k| self.slant(k, sin_z, &ext)).collect();
        let mut path = 0.0;
        for k in 0..n {
            let mut p = self.mol[k] * rayleigh(-mu_s);
            for (g, a) in &self.species {
                p += a[k] * hg(-mu_s, *g);
            }
            path += p * (-(sun[k] + top[k])).exp() * dz(k);
        }
        let direct_down =
            mu_s * (-(self.slant(0, sin_z, &ext) + 0.5 * ext(0) * dz(0) / mu_s)).exp();
        let down = self.diffuse(mu_s, &sun, &below);
        // up: the air scatters the reflector's light into the nadir view
        let up = (-total).exp() + self.diffuse(1.0, &top, &below);
        Sky {
            reflected: albedo / PI * irradiance * (direct_down + down) * up,
            path: irradiance / (4.0 * PI) * path,
        }
    }
}
