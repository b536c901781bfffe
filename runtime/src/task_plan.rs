//! Task planning (Sec. 6.1): breadth-first forward search over the blob's action templates
//! from the task's initial symbolic state to its goal, so the plan found is one of minimum
//! length. Fixed capacities: one part, three locations (ℓ0 = the platform's home, ℓ1, ℓ2).

use crate::load::{LoadError, MAX_CLASSES, Runtime};
use prf_shared::motion::symbolic::{ActionTemplate, Param, StateVar, Value};

/// Locations a task names: ℓ0 (home), ℓ1 (from), ℓ2 (to).
pub const LOCATIONS: usize = 3;
/// Index of ℓ0, ℓ1, ℓ2 among the task's locations.
pub const HOME: u8 = 0;
/// Index of ℓ1.
pub const FROM: u8 = 1;
/// Index of ℓ2.
pub const TO: u8 = 2;
/// Parts a task names.
pub const PARTS: usize = 1;
/// Maximum length of an action plan.
pub const MAX_ACTIONS: usize = 8;

/// A grounded action α_m(b): blob class `class` with symbolic arguments (part or location
/// indices, by the template's parameter kinds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Action {
    /// Blob class index.
    pub class: u8,
    /// Arguments (part or location indices).
    pub args: [u8; 3],
    /// Number of arguments used.
    pub n_args: u8,
}

/// An action plan a = (a_1 … a_N).
pub type ActionPlan = heapless::Vec<Action, MAX_ACTIONS>;

/// The symbolic state: at(p, ℓ) and robAt(ℓ) as bit masks over the task's locations,
/// holding() as 0 (None) or 1 + part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct State {
    at: u8,
    rob_at: u8,
    holding: u8,
}

/// Number of distinct states (key space of [`State::key`]).
const STATES: usize = 1 << (LOCATIONS + LOCATIONS + 1);

impl State {
    fn key(&self) -> usize {
        self.at as usize | (self.rob_at as usize) << LOCATIONS | (self.holding as usize) << 6
    }

    /// Truth of `var(args) = value` under a grounding.
    fn holds(&self, var: StateVar, args: &[u8], value: Value, b: &[u8; 3]) -> bool {
        let arg = |i: usize| args.get(i).map(|&a| b[a as usize]);
        match (var, value) {
            (StateVar::At, Value::True | Value::False) => match (arg(0), arg(1)) {
                (Some(_), Some(l)) => (self.at >> l & 1 == 1) == (value == Value::True),
                _ => false,
            },
            (StateVar::RobAt, Value::True | Value::False) => match arg(0) {
                Some(l) => (self.rob_at >> l & 1 == 1) == (value == Value::True),
                None => false,
            },
            (StateVar::Holding, Value::Nothing) => self.holding == 0,
            (StateVar::Holding, Value::Param(i)) => self.holding == 1 + b[i as usize],
            _ => false,
        }
    }

    /// Applies `var(args) := value`; false for an atom that cannot be an effect.
    fn set(&mut self, var: StateVar, args: &[u8], value: Value, b: &[u8; 3]) -> bool {
        let arg = |i: usize| args.get(i).map(|&a| b[a as usize]);
        let bit = |mask: &mut u8, l: u8| {
            if value == Value::True {
                *mask |= 1 << l
            } else {
                *mask &= !(1 << l)
            }
        };
        match (var, value) {
            (StateVar::At, Value::True | Value::False) => match arg(1) {
                Some(l) => bit(&mut self.at, l),
                None => return false,
            },
            (StateVar::RobAt, Value::True | Value::False) => match arg(0) {
                Some(l) => bit(&mut self.rob_at, l),
                None => return false,
            },
            (StateVar::Holding, Value::Nothing) => self.holding = 0,
            (StateVar::Holding, Value::Param(i)) => self.holding = 1 + b[i as usize],
            _ => return false,
        }
        true
    }
}

/// Successor of `s` under template `t` grounded with `b`, if its preconditions hold.
fn apply(t: &ActionTemplate, s: &State, b: &[u8; 3]) -> Option<State> {
    if !t.pre.iter().all(|a| s.holds(a.var, &a.args, a.value, b)) {
        return None;
    }
    let mut next = *s;
    for a in &t.eff {
        if !next.set(a.var, &a.args, a.value, b) {
            return None;
        }
    }
    Some(next)
}

/// Every grounding of the template's parameters over the task's objects, in lexicographic
/// order.
fn groundings(t: &ActionTemplate, mut out: impl FnMut([u8; 3])) {
    let radix = |p: &Param| match p {
        Param::Part => PARTS,
        Param::Location => LOCATIONS,
    };
    let n = t.params.len();
    let total: usize = t.params.iter().map(radix).product();
    for mut code in 0..total {
        let mut b = [0u8; 3];
        for i in (0..n).rev() {
            let r = radix(&t.params[i]);
            b[i] = (code % r) as u8;
            code /= r;
        }
        out(b);
    }
}

/// Forward breadth-first search from "part at ℓ1, robot at ℓ0, holding nothing" to "part at
/// ℓ2, robot at ℓ0, holding nothing". `None` when the templates cannot reach the goal.
pub fn plan_actions(rt: &Runtime<'_>) -> Result<Option<ActionPlan>, LoadError> {
    let mut templates: heapless::Vec<ActionTemplate, MAX_CLASSES> = heapless::Vec::new();
    for c in 0..rt.class_count() {
        // class_count() ≤ MAX_CLASSES by construction of the runtime.
        let _ = templates.push(rt.blob.class(c)?.action);
    }
    let start = State {
        at: 1 << FROM,
        rob_at: 1 << HOME,
        holding: 0,
    };
    let goal = State {
        at: 1 << TO,
        rob_at: 1 << HOME,
        holding: 0,
    };
    let mut parent: [Option<(u16, Action)>; STATES] = [None; STATES];
    let mut seen = [false; STATES];
    let mut queue: heapless::Deque<State, STATES> = heapless::Deque::new();
    seen[start.key()] = true;
    let _ = queue.push_back(start);
    while let Some(s) = queue.pop_front() {
        if s == goal {
            let mut plan = ActionPlan::new();
            let mut k = s.key();
            while let Some((p, a)) = parent[k] {
                if plan.push(a).is_err() {
                    return Ok(None);
                }
                k = p as usize;
            }
            plan.reverse();
            return Ok(Some(plan));
        }
        for (c, t) in templates.iter().enumerate() {
            groundings(t, |b| {
                if let Some(n) = apply(t, &s, &b) {
                    let k = n.key();
                    if k < STATES && !seen[k] {
                        seen[k] = true;
                        parent[k] = Some((
                            s.key() as u16,
                            Action {
                                class: c as u8,
                                args: b,
                                n_args: t.params.len() as u8,
                            },
                        ));
                        // Each state enters the queue at most once: it cannot overflow.
                        let _ = queue.push_back(n);
                    }
                }
            });
        }
    }
    Ok(None)
}
