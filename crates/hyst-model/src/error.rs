//! What is wrong with a model's parameters ([`ModelError`]) and the checks that say it.

/// Errors of invalid model parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// A parameter is NaN or infinite.
    #[error("parameter `{name}` is not finite: {value}")]
    NonFinite {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter that must be strictly positive is not.
    #[error("parameter `{name}` must be > 0, got {value}")]
    NonPositive {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter that must not be negative is.
    #[error("parameter `{name}` must be >= 0, got {value}")]
    Negative {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A linear state-space form was asked of a model with nonlinear terms.
    #[error("the model is not linear: it has {what}")]
    NotLinear {
        /// Which nonlinear term is present.
        what: &'static str,
    },
}

pub(crate) fn finite(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ModelError::NonFinite { name, value })
    }
}

pub(crate) fn not_negative(name: &'static str, value: f64) -> Result<(), ModelError> {
    finite(name, value)?;
    if value >= 0.0 {
        Ok(())
    } else {
        Err(ModelError::Negative { name, value })
    }
}

pub(crate) fn positive(name: &'static str, value: f64) -> Result<(), ModelError> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(ModelError::NonPositive { name, value })
    }
}
