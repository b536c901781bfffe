//! The planning domain of part transportation (Sec. 5.3.2): state variables at, robAt,
//! holding over symbolic names, and action templates α = (head, pre, eff) over them.

use heapless::Vec;
use serde::{Deserialize, Serialize};

/// Maximum parameters of an action template.
pub const MAX_PARAMS: usize = 3;
/// Maximum atoms of a precondition or effect list.
pub const MAX_ATOMS: usize = 6;

/// State variables SV = {at, robAt, holding}.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum StateVar {
    /// at(part, location) ∈ {True, False}.
    At,
    /// robAt(location) ∈ {True, False}.
    RobAt,
    /// holding() ∈ {None, part}.
    Holding,
}

/// Kind of an action parameter (a symbolic name of B).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Param {
    /// A part.
    Part,
    /// A location.
    Location,
}

/// The value an atom requires or sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Value {
    /// True.
    True,
    /// False.
    False,
    /// `None` of B: holding nothing.
    Nothing,
    /// The action's parameter with this index.
    Param(u8),
}

/// An atomic formula var(args…) = value; `args` are indices into the action's parameters.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Atom {
    /// The state variable.
    pub var: StateVar,
    /// Its arguments.
    pub args: Vec<u8, 2>,
    /// The value.
    pub value: Value,
}

impl Atom {
    /// `var(args) = value`; `args` longer than 2 is a programming error caught by tests.
    pub fn new(var: StateVar, args: &[u8], value: Value) -> Self {
        Atom {
            var,
            args: Vec::from_slice(args).unwrap_or_default(),
            value,
        }
    }
}

/// α = (head, pre, eff).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ActionTemplate {
    /// The action's name.
    pub head: heapless::String<16>,
    /// Kinds of its parameters.
    pub params: Vec<Param, MAX_PARAMS>,
    /// Preconditions.
    pub pre: Vec<Atom, MAX_ATOMS>,
    /// Effects.
    pub eff: Vec<Atom, MAX_ATOMS>,
}

impl ActionTemplate {
    /// Every atom names only the template's own parameters (its arguments and a
    /// `Value::Param`): what a blob's template must satisfy before it is grounded.
    pub fn is_well_formed(&self) -> bool {
        let n = self.params.len();
        self.pre.iter().chain(&self.eff).all(|a| {
            a.args.iter().all(|&i| (i as usize) < n)
                && !matches!(a.value, Value::Param(i) if i as usize >= n)
        })
    }

    /// Builds a template; inputs beyond the fixed capacities are a programming error caught
    /// by the motion-class tests (the result would lack them).
    pub fn new(head: &str, params: &[Param], pre: &[Atom], eff: &[Atom]) -> Self {
        let mut h = heapless::String::new();
        let _ = h.push_str(head);
        ActionTemplate {
            head: h,
            params: Vec::from_slice(params).unwrap_or_default(),
            pre: pre.iter().cloned().collect(),
            eff: eff.iter().cloned().collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in classes' templates are well formed; an atom that names a parameter the
    /// template lacks (as a corrupt blob can) is not.
    #[test]
    fn a_template_names_only_its_own_parameters() {
        for c in crate::motion::CLASSES {
            assert!(c.action().is_well_formed(), "{}", c.name());
        }
        let p = [Param::Part, Param::Location];
        let ok = ActionTemplate::new(
            "a",
            &p,
            &[Atom::new(StateVar::At, &[0, 1], Value::True)],
            &[],
        );
        assert!(ok.is_well_formed());
        let arg = ActionTemplate::new(
            "a",
            &p,
            &[Atom::new(StateVar::At, &[0, 253], Value::True)],
            &[],
        );
        assert!(!arg.is_well_formed());
        let value = ActionTemplate::new(
            "a",
            &p,
            &[],
            &[Atom::new(StateVar::Holding, &[], Value::Param(2))],
        );
        assert!(!value.is_well_formed());
    }
}
