//! Option strings, parsed once.
//!
//! Every option that a caller names by a string (a subspace weighting, a compressor, an
//! integrator, a nonlinearity kind, ...) is an enum of the core with a `FromStr` built by
//! [`option_names!`](crate::names): a fixed table of names, the first name of each value its
//! canonical one, and one error, [`SysidError::InvalidArgument`] naming the option, what it
//! accepts and what it got. The bindings and the Python layer ask the core ([`canonical`])
//! instead of keeping lists of their own.
//!
//! ```
//! use sysid_core::names::canonical;
//! assert_eq!(canonical("method", "PO-MOESP").unwrap(), "moesp");
//! let e = canonical("integrator", "euler").unwrap_err().to_string();
//! assert_eq!(
//!     e,
//!     "invalid integrator: unknown integrator \"euler\"; integrator must be \"rk4\" or \"adaptive\""
//! );
//! ```

use crate::error::{Result, SysidError};
use std::str::FromStr;

/// An option enum parsed from a table of names.
pub trait OptionName: FromStr<Err = SysidError> {
    /// The option's name, as the error says it (`"integrator"`).
    const OPTION: &'static str;
    /// The canonical name of this value (the first name of its variant in the table).
    fn option_name(&self) -> &'static str;
}

/// The value named `s` in `table`, or an error on option `name` listing the names accepted.
pub(crate) fn choose<T: Clone>(name: &'static str, s: &str, table: &[(&str, T)]) -> Result<T> {
    if let Some((_, v)) = table.iter().find(|(key, _)| *key == s) {
        return Ok(v.clone());
    }
    let keys: Vec<String> = table.iter().map(|(k, _)| format!("{k:?}")).collect();
    let list = match keys.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    Err(SysidError::invalid(
        name,
        format!("unknown {name} {s:?}; {name} must be {list}"),
    ))
}

/// `FromStr` and [`OptionName`] for an enum from its table of names; with `lowercase`, the
/// string is matched ignoring ASCII case. Payload-carrying variants take default payloads
/// in the table (the caller sets them after parsing).
macro_rules! option_names {
    ($ty:ty, $name:literal, $lower:literal, [$(($key:literal, $val:expr)),+ $(,)?]) => {
        impl std::str::FromStr for $ty {
            type Err = $crate::error::SysidError;

            fn from_str(s: &str) -> $crate::error::Result<Self> {
                let table: &[(&str, $ty)] = &[$(($key, $val)),+];
                if $lower {
                    let low = s.to_ascii_lowercase();
                    if let Ok(v) = $crate::names::choose($name, &low, table) {
                        return Ok(v);
                    }
                }
                $crate::names::choose($name, s, table)
            }
        }

        impl $crate::names::OptionName for $ty {
            const OPTION: &'static str = $name;

            fn option_name(&self) -> &'static str {
                let table: &[(&'static str, $ty)] = &[$(($key, $val)),+];
                let d = std::mem::discriminant(self);
                table
                    .iter()
                    .find(|(_, v)| std::mem::discriminant(v) == d)
                    .map_or("", |(k, _)| *k)
            }
        }
    };
}
pub(crate) use option_names;

fn name_of<T: OptionName>(value: &str) -> Result<&'static str> {
    Ok(value.parse::<T>()?.option_name())
}

/// The options [`canonical`] knows, by the name a caller asks with.
pub const OPTIONS: &[&str] = &[
    "method",
    "matrices",
    "closed_loop_method",
    "compressor",
    "regularization",
    "factor_source",
    "realization",
    "fir_regularization",
    "integrator",
    "jacobian",
    "terms",
    "recursive_method",
    "nonlinearity",
];

/// The canonical name of `value` for the option `option` (one of [`OPTIONS`]), or the
/// option's own error when the value is not one of its names.
pub fn canonical(option: &str, value: &str) -> Result<&'static str> {
    use crate::{greybox::ode, hankel, hw, nlss, realization, recursive, subspace};
    match option {
        "method" => name_of::<subspace::Method>(value),
        "matrices" => name_of::<subspace::SystemMatrices>(value),
        "closed_loop_method" => name_of::<subspace::closed_loop::ClosedLoopMethod>(value),
        "compressor" => name_of::<hankel::CompressorKind>(value),
        "regularization" => name_of::<subspace::closed_loop::VarxRegularization>(value),
        "factor_source" => name_of::<hankel::FactorSource>(value),
        "realization" => name_of::<realization::RealizationMethod>(value),
        "fir_regularization" => name_of::<realization::Regularization>(value),
        "integrator" => name_of::<ode::Integrator>(value),
        "jacobian" => name_of::<ode::OdeJacobian>(value),
        "terms" => name_of::<nlss::Terms>(value),
        "recursive_method" => name_of::<recursive::Method>(value),
        "nonlinearity" => name_of::<hw::Nonlinearity>(value),
        other => Err(SysidError::invalid(
            "option",
            format!("unknown option {other:?}; known: {}", OPTIONS.join(", ")),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_option_parses_its_canonical_name_and_refuses_others() {
        for opt in OPTIONS {
            let err = canonical(opt, "no-such-name").unwrap_err();
            assert!(
                matches!(err, SysidError::InvalidArgument { .. }),
                "{opt}: {err}"
            );
            assert!(
                err.to_string().contains(" \"no-such-name\"; "),
                "{opt}: {err}"
            );
        }
        assert!(canonical("colour", "red").is_err());
        for (opt, name) in [
            ("method", "n4sid"),
            ("closed_loop_method", "ssarx"),
            ("compressor", "qr"),
            ("regularization", "tc"),
            ("factor_source", "qr-fallback"),
            ("realization", "era"),
            ("fir_regularization", "none"),
            ("integrator", "adaptive"),
            ("jacobian", "sensitivity"),
            ("terms", "states"),
            ("recursive_method", "kalman"),
            ("nonlinearity", "pwl"),
        ] {
            assert_eq!(canonical(opt, name).unwrap(), name);
        }
    }

    #[test]
    fn aliases_map_to_the_canonical_name() {
        assert_eq!(canonical("method", "po-moesp").unwrap(), "moesp");
        assert_eq!(canonical("method", "CVA").unwrap(), "cva");
        assert_eq!(
            canonical("closed_loop_method", "pbsid-opt").unwrap(),
            "pbsid"
        );
    }

    #[test]
    fn the_error_lists_the_names() {
        let e = choose("x", "c", &[("a", 1), ("b", 2)]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "invalid x: unknown x \"c\"; x must be \"a\" or \"b\""
        );
    }
}
