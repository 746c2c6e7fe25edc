//! The value of `--shard`: `K/N`, or `auto`, the shard an array job's environment gives.

use super::cut::Shard;
use super::env;
use crate::error::Result;

/// The value of `--shard`: `K/N`, or `auto` (from the environment of an array job).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardArg {
    /// `K/N`.
    Fixed(Shard),
    /// `auto`: [`env::from_environment`].
    Auto,
}

impl std::str::FromStr for ShardArg {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let s = s.trim();
        if s == "auto" {
            return Ok(ShardArg::Auto);
        }
        let form = || format!("{s:?} is not K/N (e.g. 0/4) or auto");
        let (k, n) = s.split_once('/').ok_or_else(form)?;
        let k: usize = k.trim().parse().map_err(|_| form())?;
        let n: usize = n.trim().parse().map_err(|_| form())?;
        Shard::new(k, n).map(ShardArg::Fixed)
    }
}

impl ShardArg {
    /// The shard: as given, or read from this process's environment.
    pub fn resolve(self) -> Result<Shard> {
        match self {
            ShardArg::Fixed(s) => Ok(s),
            ShardArg::Auto => env::from_environment(|name| std::env::var(name).ok()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_arguments_parse_or_say_why_not() {
        assert_eq!(
            "2/4".parse::<ShardArg>(),
            Ok(ShardArg::Fixed(Shard { index: 2, count: 4 }))
        );
        assert_eq!("auto".parse::<ShardArg>(), Ok(ShardArg::Auto));
        assert!(
            "4/4"
                .parse::<ShardArg>()
                .unwrap_err()
                .contains("0 to N-1 = 3")
        );
        assert!(
            "0/0"
                .parse::<ShardArg>()
                .unwrap_err()
                .contains("at least 1")
        );
        assert!("x".parse::<ShardArg>().unwrap_err().contains("K/N"));
        let s = Shard::new(0, 5).unwrap();
        assert!(s.rows_of(4, "profiles").is_err());
        assert_eq!(s.rows_of(5, "profiles").unwrap(), 0..1);
    }
}
