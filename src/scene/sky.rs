//! The daylight sky a nadir view sees from space (docs/model.md §4f, "Sky light from
//! space by day"): the sunlight reflected below, and the sunlight the air above the
//! reflector scatters once into the view (path radiance).
//!
//! **Column.** [`SkyColumn::above`] takes the atmosphere's own piecewise-constant
//! column at the channel's (detected) wavelength from the reflector to the top
//! (`Atmosphere::slabs`) and merges neighbouring slabs into sky layers of at most
//! [`LAYER_DEPTH_MAX`] optical depth and [`LAYER_THICKNESS_MAX_M`] thickness, never
//! across an aerosol or cloud layer's edge. Each sky layer keeps the optical depths of
//! its scatterers by phase function — molecules (Rayleigh), and the particles grouped by
//! asymmetry factor g (the background aerosol's 0.7, each layer's `asymmetry_factor`:
//! 0.85 water, 0.75 ice, 0.7 aerosol) — and of its absorber, ozone. Built once per
//! column and channel; a night or fixed-background scene builds none.
//!
//! **Solar path: spherical.** The sun's slant optical depth from the bottom of layer i
//! (radius r_i = R⊕ + z_i) to the top is `S_i = Σ_{j≥i} (dτ_j/dz_j)·c_j(p_i)`, with the
//! straight ray's impact parameter `p_i = r_i·sin θ_s` and its chord through shell j,
//! `c_j(p) = √(r_{j+1}² − p²) − √(r_j² − p²)` (no refraction, as the solar position).
//! For the molecular column of US76 this air mass is 10.20 at 85° and 18.82 at 88°,
//! 1.0 % and 3.1 % below Kasten & Young's (1989) ([`kasten_young_air_mass`], tested),
//! who integrate along the refracted ray; for the aerosol (scale height ~1 km) it is
//! nearer the plane-parallel 1/μ_s, as it should be. Within a layer the slant depth is
//! taken linear between its edges.
//!
//! **View path: plane-parallel, nadir** (μ_v = 1: CALIOP's 3° off nadir changes 1/μ_v
//! by 0.14 %), scattering angle Θ = 180° − θ_s.
//!
//! **Single scattering.** With `V_i` the vertical optical depth above edge i,
//! `A_i = S_{i+1} + V_{i+1}`, `B_i = (S_i − S_{i+1}) + dτ_i`:
//!
//! ```text
//! L_path = F/(4π) · Σ_i [dτ_mol,i·P_R(Θ) + Σ_g dτ_g,i·P_HG(Θ; g)] · e^{−A_i}·(1 − e^{−B_i})/B_i
//! P_R(Θ) = (3/4)(1 + cos²Θ)          (no depolarization correction: 1.4 % at 532 nm)
//! P_HG(Θ; g) = (1 − g²)/(1 + g² − 2g·cos Θ)^{3/2}
//! ```
//!
//! the exact integral of `F/(4π)·σ(z)·P·e^{−S(z)−V(z)}` over a homogeneous layer; for one
//! homogeneous plane-parallel layer it is the path reflectance
//! `R = P/(4(μ_s + 1))·(1 − e^{−τ(1/μ_s + 1)})` with `L = R·F·μ_s/π`.
//!
//! **Reflected term.** A Lambertian reflector of albedo ρ under the direct beam
//! `F·μ_s·e^{−S_0}` and the once-scattered diffuse irradiance
//!
//! ```text
//! E_d = F · Σ_i [e^{−S_{i+1}}·(1 − e^{−ΔS_i})/ΔS_i] · Σ_species dτ_i·H(τ_below,i),
//! H(t) = 1/(4π) ∫_{down} P(Θ') e^{−t/μ'} dΩ'
//! ```
//!
//! (τ_below,i from the layer's mid-height to the reflector, H by a 12 × 24
//! Gauss–Legendre × azimuth rule; for molecules H(0) = ½), seen through the direct
//! `e^{−V_0}` and the reflected light the air scatters once into the view, which for a
//! uniform Lambertian reflector is by reciprocity `t_d = E_d(μ_s = 1)/F` (built once):
//! `L_refl = ρ/π·(F·μ_s·e^{−S_0} + E_d)·(e^{−V_0} + t_d)`.
//!
//! **Order kept: single** (docs/model.md and validation/reports/daylight_sky.md give
//! its error: a second order adds 16 % (60°) to 21 % (85°) of the molecular path
//! radiance, ~50 % with the 23 km aerosol; the ground–air coupling `1/(1 − ρ·s)`,
//! s ≈ 0.08, left out, is +6.5 % of the reflected term over snow). Twilight (θ_s ≥ 90°)
//! is not modelled.

use crate::atmosphere::{Atmosphere, BackgroundAerosol};
use crate::constants::EARTH_RADIUS_M;
use std::f64::consts::PI;

/// Largest optical depth of a sky layer: `(1/μ_s + 1)·dτ ≤ 0.06` at 85°.
pub const LAYER_DEPTH_MAX: f64 = 0.005;
/// Largest thickness of a sky layer, m.
pub const LAYER_THICKNESS_MAX_M: f64 = 2_000.0;
/// Gauss–Legendre nodes on μ' ∈ (0, 1) for the diffuse irradiance.
const DIFFUSE_MU_NODES: usize = 12;
/// Azimuth nodes on [0, 2π) for the diffuse irradiance.
const DIFFUSE_AZIMUTH_NODES: usize = 24;

/// Kasten & Young (1989, Appl. Opt. 28, 4735) relative optical air mass at zenith angle
/// `zenith_deg`: `AM = 1/(cos z + 0.50572·(96.07995 − z)^−1.6364)` (z in degrees);
/// 10.31 at 85°, 19.43 at 88°, 38.1 at 90°. The reference the spherical solar path is
/// tested against (module docs).
pub fn kasten_young_air_mass(zenith_deg: f64) -> f64 {
    1.0 / (zenith_deg.to_radians().cos() + 0.50572 * (96.07995 - zenith_deg).powf(-1.6364))
}

/// Rayleigh phase function `(3/4)(1 + cos²Θ)` (normalized to 4π over the sphere).
pub fn rayleigh_phase(cos_theta: f64) -> f64 {
    0.75 * (1.0 + cos_theta * cos_theta)
}

/// Henyey–Greenstein phase function of asymmetry `g` (normalized to 4π).
pub fn henyey_greenstein_phase(cos_theta: f64, g: f64) -> f64 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (d * d.sqrt())
}

/// One sky layer: its edges and optical depths by species.
#[derive(Debug, Clone)]
struct SkyLayer {
    z_lo: f64,
    z_hi: f64,
    /// Molecular (Rayleigh) scattering optical depth.
    molecules: f64,
    /// Ozone absorption optical depth.
    ozone: f64,
    /// Particle scattering optical depth per asymmetry class (`SkyColumn::asymmetry`).
    particles: Vec<f64>,
}

impl SkyLayer {
    fn depth(&self) -> f64 {
        self.molecules + self.ozone + self.particles.iter().sum::<f64>()
    }
}

/// The column above a reflector, as the sky sees it (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SkyColumn {
    /// Layer edges, m, from the reflector up (n + 1 of them).
    edges_m: Vec<f64>,
    /// Per layer: molecular, ozone optical depth.
    molecules: Vec<f64>,
    ozone: Vec<f64>,
    /// Per layer, per class: particle optical depth (layer-major).
    particles: Vec<f64>,
    /// The particle classes' asymmetry factors.
    asymmetry: Vec<f64>,
    /// The reflected light's transmission to the nadir view (`up_transmission`).
    up_transmission: f64,
}

/// The two parts of the daylight radiance, photons m⁻² s⁻¹ sr⁻¹ nm⁻¹.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SkyRadiance {
    /// Sunlight reflected by the surface or cloud top, through the air.
    pub reflected: f64,
    /// Sunlight scattered once by the air into the view.
    pub path: f64,
}

impl SkyRadiance {
    /// Their sum.
    pub fn total(&self) -> f64 {
        self.reflected + self.path
    }
}

/// The particle species at altitude `z_m` of `atmosphere`: (extinction m⁻¹, g).
fn particles_at(atmosphere: &Atmosphere, z_m: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    if let Some(a) = &atmosphere.aerosol {
        out.push((a.extinction_per_m(z_m), BackgroundAerosol::ASYMMETRY));
    }
    for l in &atmosphere.layers {
        if z_m >= l.base_m && z_m < l.top_m {
            out.push((l.extinction_per_m, l.asymmetry_factor));
        }
    }
    out
}

impl SkyColumn {
    /// The column of `atmosphere` (its detected line) above `reflector_m` (module docs).
    pub fn above(atmosphere: &Atmosphere, reflector_m: f64) -> SkyColumn {
        let atmosphere = atmosphere.detected_line();
        let top = atmosphere.top_m();
        let mut asymmetry: Vec<f64> = Vec::new();
        if atmosphere.aerosol.is_some() {
            asymmetry.push(BackgroundAerosol::ASYMMETRY);
        }
        for l in &atmosphere.layers {
            if !asymmetry.contains(&l.asymmetry_factor) {
                asymmetry.push(l.asymmetry_factor);
            }
        }
        let is_layer_edge = |z: f64| {
            atmosphere
                .layers
                .iter()
                .any(|l| (l.base_m - z).abs() < 1e-6 || (l.top_m - z).abs() < 1e-6)
        };
        let mut layers: Vec<SkyLayer> = Vec::new();
        let slabs = if top > reflector_m {
            atmosphere.slabs(reflector_m, top)
        } else {
            Vec::new()
        };
        for slab in slabs {
            let dz = slab.z_hi - slab.z_lo;
            let mid = 0.5 * (slab.z_lo + slab.z_hi);
            let o = slab.optics;
            let mut particles = vec![0.0; asymmetry.len()];
            for (alpha, g) in particles_at(atmosphere, mid) {
                let k = asymmetry.iter().position(|&a| a == g).unwrap_or(0);
                particles[k] += alpha * dz;
            }
            let add = SkyLayer {
                z_lo: slab.z_lo,
                z_hi: slab.z_hi,
                molecules: o.alpha_mol * dz,
                ozone: o.alpha_o3 * dz,
                particles,
            };
            match layers.last_mut() {
                Some(last)
                    if !is_layer_edge(last.z_hi)
                        && last.depth() + add.depth() <= LAYER_DEPTH_MAX
                        && add.z_hi - last.z_lo <= LAYER_THICKNESS_MAX_M =>
                {
                    last.z_hi = add.z_hi;
                    last.molecules += add.molecules;
                    last.ozone += add.ozone;
                    for (a, b) in last.particles.iter_mut().zip(&add.particles) {
                        *a += b;
                    }
                }
                _ => layers.push(add),
            }
        }
        let mut edges_m: Vec<f64> = layers.iter().map(|l| l.z_lo).collect();
        edges_m.push(layers.last().map_or(reflector_m, |l| l.z_hi));
        let mut column = SkyColumn {
            edges_m,
            molecules: layers.iter().map(|l| l.molecules).collect(),
            ozone: layers.iter().map(|l| l.ozone).collect(),
            particles: layers.iter().flat_map(|l| l.particles.clone()).collect(),
            asymmetry,
            up_transmission: 1.0,
        };
        column.up_transmission = column.up_transmission();
        column
    }

    /// The number of sky layers.
    pub fn n_layers(&self) -> usize {
        self.molecules.len()
    }

    fn particle_depths(&self, i: usize) -> &[f64] {
        let k = self.asymmetry.len();
        &self.particles[i * k..(i + 1) * k]
    }

    /// Layer i's total (extinction) optical depth.
    fn layer_depth(&self, i: usize) -> f64 {
        self.molecules[i] + self.ozone[i] + self.particle_depths(i).iter().sum::<f64>()
    }

    /// Vertical optical depths above the reflector: (scattering, absorbing).
    pub fn vertical_depths(&self) -> (f64, f64) {
        let n = self.n_layers();
        let sca: f64 = (0..n)
            .map(|i| self.molecules[i] + self.particle_depths(i).iter().sum::<f64>())
            .sum();
        (sca, self.ozone.iter().sum())
    }

    /// The sun's slant optical depth from edge `i` to the top at `sin_zenith` (module
    /// docs), through layers whose depth is `depth(j)`.
    fn slant_depth(&self, i: usize, sin_zenith: f64, depth: impl Fn(usize) -> f64) -> f64 {
        let r = |k: usize| EARTH_RADIUS_M + self.edges_m[k];
        let p2 = (r(i) * sin_zenith).powi(2);
        let mut lower = r(i) * (1.0 - sin_zenith * sin_zenith).max(0.0).sqrt();
        let mut sum = 0.0;
        for j in i..self.n_layers() {
            let upper = (r(j + 1) * r(j + 1) - p2).max(0.0).sqrt();
            let dz = self.edges_m[j + 1] - self.edges_m[j];
            if dz > 0.0 {
                sum += depth(j) / dz * (upper - lower);
            }
            lower = upper;
        }
        sum
    }

    /// The molecular column's air mass at `zenith_deg` (< 90°): its slant optical depth
    /// from the reflector over its vertical one, the spherical solar path of the module
    /// docs (compare [`kasten_young_air_mass`]).
    pub fn molecular_air_mass(&self, zenith_deg: f64) -> f64 {
        let vertical: f64 = self.molecules.iter().sum();
        self.slant_depth(0, zenith_deg.to_radians().sin(), |j| self.molecules[j]) / vertical
    }

    /// The daylight radiance at solar zenith `zenith_deg` over a reflector of albedo
    /// `albedo`, under the top-of-atmosphere irradiance `irradiance` (photons m⁻² s⁻¹
    /// nm⁻¹): the reflected term and, if `path_radiance`, the air's (module docs); 0 with
    /// the sun at or below the horizon.
    pub fn radiance(
        &self,
        albedo: f64,
        irradiance: f64,
        zenith_deg: f64,
        path_radiance: bool,
    ) -> SkyRadiance {
        if zenith_deg.abs() >= 90.0 || zenith_deg.is_nan() {
            return SkyRadiance::default();
        }
        let n = self.n_layers();
        let (sin_z, mu_s) = zenith_deg.to_radians().sin_cos();
        let depth: Vec<f64> = (0..n).map(|i| self.layer_depth(i)).collect();
        let slant: Vec<f64> = (0..=n)
            .map(|i| self.slant_depth(i, sin_z, |j| depth[j]))
            .collect();
        let above = self.depths_above();
        let mut path = 0.0;
        if path_radiance {
            for i in 0..n {
                let b = slant[i] - slant[i + 1] + self.layer_depth(i);
                let source = self.molecules[i] * rayleigh_phase(-mu_s)
                    + self
                        .particle_depths(i)
                        .iter()
                        .zip(&self.asymmetry)
                        .map(|(t, &g)| t * henyey_greenstein_phase(-mu_s, g))
                        .sum::<f64>();
                path += source * (-(slant[i + 1] + above[i + 1])).exp() * exp_ratio(b);
            }
        }
        let down = self.diffuse(mu_s, &slant, &above);
        SkyRadiance {
            reflected: albedo / PI
                * irradiance
                * (mu_s * (-slant[0]).exp() + down)
                * self.up_transmission,
            path: irradiance / (4.0 * PI) * path,
        }
    }

    /// Vertical optical depth above each edge (n + 1 values, 0 at the top).
    fn depths_above(&self) -> Vec<f64> {
        let n = self.n_layers();
        let mut above = vec![0.0; n + 1];
        for i in (0..n).rev() {
            above[i] = above[i + 1] + self.layer_depth(i);
        }
        above
    }

    /// The once-scattered diffuse irradiance reaching the reflector per unit F (module
    /// docs, `E_d/F`) of a beam of direction cosine `mu` whose optical depth from edge i
    /// to the top is `slant[i]`; `above` the vertical depths ([`Self::depths_above`]).
    fn diffuse(&self, mu: f64, slant: &[f64], above: &[f64]) -> f64 {
        let kernel = DiffuseKernel::new(mu, &self.asymmetry);
        (0..self.n_layers())
            .map(|i| {
                let d_tau = self.layer_depth(i);
                let below = above[0] - above[i] + 0.5 * d_tau;
                (-slant[i + 1]).exp()
                    * exp_ratio(slant[i] - slant[i + 1])
                    * kernel.irradiance(below, self.molecules[i], self.particle_depths(i))
            })
            .sum()
    }

    /// The reflected light's transmission to a nadir view: the direct `e^{−V_0}` plus the
    /// once-scattered part, which for a uniform Lambertian reflector is, by reciprocity,
    /// the diffuse irradiance of an overhead sun ([`Self::diffuse`] at μ = 1).
    fn up_transmission(&self) -> f64 {
        let above = self.depths_above();
        (-above[0]).exp() + self.diffuse(1.0, &above, &above)
    }

    /// An upper bound of the path radiance at any solar angle under `irradiance`:
    /// `F/(4π)·Σ dτ·max P` over Θ ∈ [90°, 180°].
    pub fn path_radiance_bound(&self, irradiance: f64) -> f64 {
        let n = self.n_layers();
        let sum: f64 = (0..n)
            .map(|i| {
                self.molecules[i] * 1.5
                    + self
                        .particle_depths(i)
                        .iter()
                        .zip(&self.asymmetry)
                        .map(|(t, &g)| t * henyey_greenstein_phase(0.0, g.max(0.0)))
                        .sum::<f64>()
            })
            .sum();
        irradiance / (4.0 * PI) * sum
    }
}

/// `(1 − e^{−x})/x`, 1 at x = 0.
fn exp_ratio(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0 - 0.5 * x
    } else {
        -(-x).exp_m1() / x
    }
}

/// The downward hemisphere's weights of the diffuse irradiance for a sun at μ_s:
/// per μ' node, `w_j·Σ_k P(Θ'_jk)·Δφ/(4π)` for molecules and each particle class.
struct DiffuseKernel {
    mu: [f64; DIFFUSE_MU_NODES],
    molecules: [f64; DIFFUSE_MU_NODES],
    particles: Vec<[f64; DIFFUSE_MU_NODES]>,
}

impl DiffuseKernel {
    fn new(mu_s: f64, asymmetry: &[f64]) -> Self {
        let (x, w) = gauss_legendre_unit();
        let sin_s = (1.0 - mu_s * mu_s).max(0.0).sqrt();
        let d_phi = 2.0 * PI / DIFFUSE_AZIMUTH_NODES as f64;
        let mut molecules = [0.0; DIFFUSE_MU_NODES];
        let mut particles = vec![[0.0; DIFFUSE_MU_NODES]; asymmetry.len()];
        for j in 0..DIFFUSE_MU_NODES {
            let sin_d = (1.0 - x[j] * x[j]).sqrt();
            for k in 0..DIFFUSE_AZIMUTH_NODES {
                let phi = (k as f64 + 0.5) * d_phi;
                // both directions point down: the sun's travel and the scattered light's
                let cos_theta = mu_s * x[j] + sin_s * sin_d * phi.cos();
                let weight = w[j] * d_phi / (4.0 * PI);
                molecules[j] += weight * rayleigh_phase(cos_theta);
                for (p, &g) in particles.iter_mut().zip(asymmetry) {
                    p[j] += weight * henyey_greenstein_phase(cos_theta, g);
                }
            }
        }
        DiffuseKernel {
            mu: x,
            molecules,
            particles,
        }
    }

    /// `Σ_species dτ·H(t)` for a layer of these depths `t` above the reflector.
    fn irradiance(&self, t: f64, molecules: f64, particles: &[f64]) -> f64 {
        (0..DIFFUSE_MU_NODES)
            .map(|j| {
                let a = (-t / self.mu[j]).exp();
                let p: f64 = particles
                    .iter()
                    .zip(&self.particles)
                    .map(|(d, w)| d * w[j])
                    .sum();
                a * (molecules * self.molecules[j] + p)
            })
            .sum()
    }
}

/// The 12-point Gauss–Legendre rule mapped onto (0, 1): nodes and weights.
fn gauss_legendre_unit() -> ([f64; DIFFUSE_MU_NODES], [f64; DIFFUSE_MU_NODES]) {
    // positive nodes and weights of the 12-point rule on (−1, 1) (Abramowitz & Stegun 25.4)
    const X: [f64; 6] = [
        0.125_233_408_511_469,
        0.367_831_498_998_180,
        0.587_317_954_286_617,
        0.769_902_674_194_305,
        0.904_117_256_370_475,
        0.981_560_634_246_719,
    ];
    const W: [f64; 6] = [
        0.249_147_045_813_403,
        0.233_492_536_538_355,
        0.203_167_426_723_066,
        0.160_078_328_543_346,
        0.106_939_325_995_318,
        0.047_175_336_386_512,
    ];
    let mut x = [0.0; DIFFUSE_MU_NODES];
    let mut w = [0.0; DIFFUSE_MU_NODES];
    for k in 0..6 {
        x[2 * k] = 0.5 * (1.0 - X[k]);
        x[2 * k + 1] = 0.5 * (1.0 + X[k]);
        w[2 * k] = 0.5 * W[k];
        w[2 * k + 1] = 0.5 * W[k];
    }
    (x, w)
}
