//! What identifies an onboard product's run: its root attributes, the method of every
//! onboard run and the lidarsim that drew it.

use crate::output::raw_file::AttrValue;
use crate::output::raw_file::content::PRODUCT_ATTRIBUTE;

/// The method of every onboard run: shot by shot.
pub const METHOD: &str = "shot";

/// `lidarsim <version>`.
pub fn source() -> String {
    format!("lidarsim {}", env!("CARGO_PKG_VERSION"))
}

/// What identifies a product's run in its root attributes.
#[derive(Debug, Clone, PartialEq)]
pub struct ProductIdentity {
    /// The scheme written.
    pub scheme: String,
    /// `lidarsim <version>`.
    pub source: String,
    /// The resolved config of the native run.
    pub config: String,
    /// The seed of the counts.
    pub seed: u64,
}

/// The product's root attributes (docs/file-format.md), in order: `Conventions`,
/// `title`, `source`, `history`, `date_created`, `config`, [`PRODUCT_ATTRIBUTE`],
/// `scheme`, `seed`.
pub fn product_attributes(
    id: &ProductIdentity,
    history: &str,
    created: &str,
) -> Vec<(String, AttrValue)> {
    let text = |k: &str, v: &str| (k.to_string(), AttrValue::Str(v.to_string()));
    vec![
        text("Conventions", crate::output::raw_file::CONVENTIONS),
        text(
            "title",
            &format!("lidarsim onboard product, scheme {}", id.scheme),
        ),
        text("source", &id.source),
        text("history", history),
        text("date_created", created),
        text("config", &id.config),
        text(PRODUCT_ATTRIBUTE, "onboard"),
        text("scheme", &id.scheme),
        ("seed".into(), AttrValue::U64(id.seed)),
    ]
}
