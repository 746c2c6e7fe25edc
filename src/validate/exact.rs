//! Sums whose value does not depend on the order of their terms, so that the sums of a
//! validation cut into shards add up to the single run's bit for bit
//! (`validate --combine`, `validate::partial`).
//!
//! * counts and their squares are summed as 128-bit integers (exact);
//! * floating-point terms go into an [`ExactSum`]: Shewchuk's non-overlapping partials
//!   (J. R. Shewchuk, *Adaptive Precision Floating-Point Arithmetic and Fast Robust
//!   Geometric Predicates*, 1997; the algorithm of Python's `math.fsum`), which hold the
//!   exact sum, and whose [`ExactSum::value`] is that sum correctly rounded: one value
//!   whatever the order of the terms or the grouping into shards.
//!
//! In JSON, 128-bit integers are decimal strings and partials the bit patterns of their
//! f64 (no reader rounds either).

use serde::{Deserialize, Serialize};

/// An exact sum of finite f64 terms.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ExactSum {
    /// Non-overlapping partials, increasing in magnitude, summing exactly to the sum.
    #[serde(with = "bits")]
    partials: Vec<f64>,
}

impl ExactSum {
    /// Adds the term `x` exactly.
    pub fn add(&mut self, mut x: f64) {
        let mut kept = 0;
        for j in 0..self.partials.len() {
            let mut y = self.partials[j];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            let lo = y - (hi - x);
            if lo != 0.0 {
                self.partials[kept] = lo;
                kept += 1;
            }
            x = hi;
        }
        self.partials.truncate(kept);
        self.partials.push(x);
    }

    /// Adds every term of `other` (exactly: the sum of both).
    pub fn merge(&mut self, other: &ExactSum) {
        other.partials.iter().for_each(|&p| self.add(p));
    }

    /// Whether every partial is finite (a sum read from a file may not be).
    pub fn is_finite(&self) -> bool {
        self.partials.iter().all(|p| p.is_finite())
    }

    /// The sum, correctly rounded to f64 (round half to even).
    pub fn value(&self) -> f64 {
        let p = &self.partials;
        let mut n = p.len();
        if n == 0 {
            return 0.0;
        }
        n -= 1;
        let mut hi = p[n];
        let mut lo = 0.0;
        while n > 0 {
            let x = hi;
            n -= 1;
            let y = p[n];
            hi = x + y;
            lo = y - (hi - x);
            if lo != 0.0 {
                break;
            }
        }
        // half-way cases: the partials below decide which way to round
        if n > 0 && ((lo < 0.0 && p[n - 1] < 0.0) || (lo > 0.0 && p[n - 1] > 0.0)) {
            let y = lo * 2.0;
            let x = hi + y;
            if y == x - hi {
                hi = x;
            }
        }
        hi
    }
}

/// `Vec<f64>` as the bit patterns of its values.
mod bits {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|x| x.to_bits()))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<u64>::deserialize(d)?
            .into_iter()
            .map(f64::from_bits)
            .collect())
    }
}

/// A 128-bit integer as a decimal string.
pub mod decimal {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<T: std::fmt::Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(v)
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<T, D::Error>
    where
        T: std::str::FromStr,
        T::Err: std::fmt::Display,
        D: Deserializer<'de>,
    {
        String::deserialize(d)?.parse().map_err(D::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sum_does_not_depend_on_order_or_grouping() {
        // terms whose naive sums differ with the order
        let terms: Vec<f64> = (0..2000)
            .map(|i| {
                let x = (i as f64 * 0.7311).sin() * 10f64.powi(i % 17 - 8);
                if i % 3 == 0 { -x } else { x }
            })
            .collect();
        let whole = terms.iter().fold(ExactSum::default(), |mut s, &x| {
            s.add(x);
            s
        });
        let mut reversed = ExactSum::default();
        terms.iter().rev().for_each(|&x| reversed.add(x));
        let mut grouped = ExactSum::default();
        for chunk in terms.chunks(333) {
            let mut part = ExactSum::default();
            chunk.iter().for_each(|&x| part.add(x));
            grouped.merge(&part);
        }
        assert_eq!(whole.value().to_bits(), reversed.value().to_bits());
        assert_eq!(whole.value().to_bits(), grouped.value().to_bits());
        let naive_forward: f64 = terms.iter().sum();
        let naive_backward: f64 = terms.iter().rev().sum();
        assert_ne!(
            naive_forward.to_bits(),
            naive_backward.to_bits(),
            "a weak test"
        );
    }

    #[test]
    fn the_sum_is_correctly_rounded() {
        let mut s = ExactSum::default();
        for x in [1e100, 1.0, -1e100, 1e-30] {
            s.add(x);
        }
        assert_eq!(s.value(), 1.0 + 1e-30);
        let mut t = ExactSum::default();
        [0.1; 10].iter().for_each(|&x| t.add(x));
        assert_eq!(t.value(), 1.0);
    }

    #[test]
    fn json_keeps_every_bit() {
        let mut s = ExactSum::default();
        [0.1, 1e-17, 3.3e5].iter().for_each(|&x| s.add(x));
        let back: ExactSum = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
    }
}
