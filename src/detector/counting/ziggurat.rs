//! The standard exponential by the ziggurat (Marsaglia & Tsang 2000), for the extension's
//! first photon of a dense `RateLaw`.

use std::sync::OnceLock;

use rand::Rng;

use super::support::unit_f64;

/// Layers of the exponential ziggurat.
const ZIG_LAYERS: usize = 256;
/// Its base layer's right end r and each layer's area v (Marsaglia & Tsang 2000, for
/// 256 layers: `v = e^{−r}(r + 1)`).
const ZIG_R: f64 = 7.697_117_470_131_05;

/// The exponential ziggurat's tables: the layers' right ends `x_0 = v/e^{−r}`, `x_1 = r`,
/// `x_{i+1} = −ln(v/x_i + e^{−x_i})`, `x_256 = 0`, and `f_i = e^{−x_i}`.
pub(crate) fn ziggurat() -> &'static ([f64; ZIG_LAYERS + 1], [f64; ZIG_LAYERS + 1]) {
    static TABLES: OnceLock<([f64; ZIG_LAYERS + 1], [f64; ZIG_LAYERS + 1])> = OnceLock::new();
    TABLES.get_or_init(|| {
        let v = (-ZIG_R).exp() * (ZIG_R + 1.0);
        let mut x = [0.0; ZIG_LAYERS + 1];
        x[0] = v / (-ZIG_R).exp();
        x[1] = ZIG_R;
        for i in 1..ZIG_LAYERS - 1 {
            x[i + 1] = -(v / x[i] + (-x[i]).exp()).ln();
        }
        x[ZIG_LAYERS] = 0.0;
        let f = x.map(|xi| (-xi).exp());
        (x, f)
    })
}

/// A standard exponential by the ziggurat (Marsaglia & Tsang 2000, "The ziggurat method
/// for generating random variables", J. Stat. Softw. 5(8)), its first try from the
/// uniform `u64` `bits` (low 8 bits the layer, top 53 the abscissa): accepted at once
/// ~99 % of the time; otherwise the wedge test, or the tail `r + Exp(1)`, from `rng`.
#[inline(always)]
pub(super) fn exp1<R: Rng + ?Sized>(bits: u64, rng: &mut R) -> f64 {
    let (x, _) = ziggurat();
    let i = (bits & 0xff) as usize;
    let u = x[i] * unit_f64(bits);
    if u < x[i + 1] {
        return u;
    }
    exp1_slow(i, u, rng)
}

/// The ziggurat's wedge and tail for layer `i` and abscissa `u`, then on.
#[cold]
pub(crate) fn exp1_slow<R: Rng + ?Sized>(i: usize, u: f64, rng: &mut R) -> f64 {
    let (x, f) = ziggurat();
    let (mut i, mut u) = (i, u);
    loop {
        if i == 0 {
            // the tail beyond r: memoryless
            return ZIG_R - (1.0 - unit_f64(rng.next_u64())).ln();
        }
        if f[i] + (f[i + 1] - f[i]) * unit_f64(rng.next_u64()) < (-u).exp() {
            return u;
        }
        let bits = rng.next_u64();
        i = (bits & 0xff) as usize;
        u = x[i] * unit_f64(bits);
        if u < x[i + 1] {
            return u;
        }
    }
}
