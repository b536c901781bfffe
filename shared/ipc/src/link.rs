//! The iceoryx2 services of one cell, the one place both processes (and test observers) open
//! them, so they agree on names and sizes:
//! - `prf/<cell>/setpoint`: [`SetpointMsg`], cell → controller;
//! - `prf/<cell>/setpoint-ready`: event, cell → controller, wakes the controller;
//! - `prf/<cell>/joint-state`: [`JointStateMsg`], controller → cell.
//!
//! `<cell>` keeps concurrent cells apart (tests use unique names; `prf demo` uses its pid).

use crate::messages::{JointStateMsg, SetpointMsg};
use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

/// An iceoryx2 operation on a cell's services that failed: what was tried, and iceoryx2's
/// answer.
#[derive(Debug, thiserror::Error)]
#[error("iceoryx2: {what}: {detail}")]
pub struct IpcError {
    pub what: String,
    pub detail: String,
}

impl IpcError {
    /// `what` failed with iceoryx2's error `detail`.
    pub fn new(what: impl Into<String>, detail: impl core::fmt::Debug) -> Self {
        IpcError {
            what: what.into(),
            detail: format!("{detail:?}"),
        }
    }
}

/// The result of an IPC operation.
pub type Result<T> = core::result::Result<T, IpcError>;

/// Inter-process service of iceoryx2 (POSIX shared memory), allocating nothing per sample
/// ([`crate::recycled`]).
pub type Ipc = crate::recycled::Service;

/// Subscriber queue depth: up to 1 s of 1 kHz messages for an observer that polls slowly.
pub const QUEUE: usize = 1024;
/// Subscribers per service: the peer, plus observers (tests, tools).
const MAX_SUBSCRIBERS: usize = 8;

/// A node with iceoryx2's own log at Error (its missing-config notice is not ours to show).
/// Resources left by processes that died (killed mid-task) are removed first, so a restart
/// after a crash works.
pub fn node(name: &str) -> Result<Node<Ipc>> {
    set_log_level(LogLevel::Error);
    let node = NodeBuilder::new()
        .name(&NodeName::new(name).map_err(|e| IpcError::new(format!("node name {name:?}"), e))?)
        .create::<Ipc>()
        .map_err(|e| IpcError::new(format!("iceoryx2 node {name:?}"), e))?;
    node.try_cleanup_dead_nodes();
    Ok(node)
}

/// The controller's node name for `cell` (how a cell tells whether its controller is alive).
pub fn controller_node_name(cell: &str) -> String {
    format!("prf-firmware-sim/{cell}")
}

/// Whether a controller node of `cell` is alive. A process that died (even by SIGKILL) is
/// seen as dead at once: iceoryx2 tracks node liveness with a lock the kernel releases.
pub fn controller_alive(cell: &str) -> Result<bool> {
    with_controller(cell, |_| ())
}

/// The process id of `cell`'s live controller, as its node records it (in the controller's
/// PID namespace); `None` if no live controller node is listed or it has no process id.
pub fn controller_pid(cell: &str) -> Result<Option<i32>> {
    use iceoryx2::node::NodeView;
    let mut pid = None;
    with_controller(cell, |view| {
        pid = view.id().pid::<Ipc>().ok().map(|p| p.value());
    })?;
    Ok(pid)
}

/// Calls `found` with `cell`'s live controller node if iceoryx2 lists one; says whether it
/// did. Listing reads a directory and allocates: not for the 1 kHz loop.
fn with_controller(
    cell: &str,
    mut found: impl FnMut(&iceoryx2::node::AliveNodeView<Ipc>),
) -> Result<bool> {
    use iceoryx2::node::NodeView;
    let want = controller_node_name(cell);
    let mut alive = false;
    Node::<Ipc>::list(Config::global_config(), |state| {
        if let NodeState::Alive(view) = &state
            && view
                .details()
                .as_ref()
                .is_some_and(|d| d.name().as_str() == want)
        {
            found(view);
            alive = true;
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    })
    .map_err(|e| IpcError::new("listing iceoryx2 nodes", e))?;
    Ok(alive)
}

fn service_name(cell: &str, what: &str) -> Result<ServiceName> {
    let s = format!("prf/{cell}/{what}");
    ServiceName::new(&s).map_err(|e| IpcError::new(format!("service name {s:?}"), e))
}

fn topic<T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    cell: &str,
    what: &str,
) -> Result<iceoryx2::service::port_factory::publish_subscribe::PortFactory<Ipc, T, ()>> {
    let name = service_name(cell, what)?;
    node.service_builder(&name)
        .publish_subscribe::<T>()
        .max_publishers(1)
        .max_subscribers(MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(QUEUE)
        .history_size(0)
        .open_or_create()
        .map_err(|e| IpcError::new(format!("service {name}"), e))
}

fn subscriber<T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    cell: &str,
    what: &str,
) -> Result<Subscriber<Ipc, T, ()>> {
    topic::<T>(node, cell, what)?
        .subscriber_builder()
        .buffer_size(QUEUE)
        .create()
        .map_err(|e| IpcError::new(format!("subscriber of prf/{cell}/{what}"), e))
}

fn publisher<T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    cell: &str,
    what: &str,
) -> Result<Publisher<Ipc, T, ()>> {
    topic::<T>(node, cell, what)?
        .publisher_builder()
        .create()
        .map_err(|e| IpcError::new(format!("publisher of prf/{cell}/{what}"), e))
}

fn event(
    node: &Node<Ipc>,
    cell: &str,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<Ipc>> {
    let name = service_name(cell, "setpoint-ready")?;
    node.service_builder(&name)
        .event()
        .open_or_create()
        .map_err(|e| IpcError::new(format!("service {name}"), e))
}

/// Sends one message (loan a sample in shared memory, write it, publish it).
fn send<T: core::fmt::Debug + ZeroCopySend>(p: &Publisher<Ipc, T, ()>, msg: T) -> Result<()> {
    let sample = p.loan_uninit().map_err(|e| IpcError::new("loan", e))?;
    sample
        .write_payload(msg)
        .send()
        .map_err(|e| IpcError::new("send", e))?;
    Ok(())
}

/// Hands every message received since the last call to `f`, oldest first.
fn drain<T: core::fmt::Debug + ZeroCopySend + Copy>(
    s: &Subscriber<Ipc, T, ()>,
    mut f: impl FnMut(T),
) -> Result<()> {
    while let Some(sample) = s.receive().map_err(|e| IpcError::new("receive", e))? {
        f(*sample);
    }
    Ok(())
}

/// The cell's ports: publishes setpoints and wakes the controller, reads joint states.
pub struct CellPorts {
    pub setpoint: Publisher<Ipc, SetpointMsg, ()>,
    pub ready: Notifier<Ipc>,
    pub joint_state: Subscriber<Ipc, JointStateMsg, ()>,
}

impl CellPorts {
    /// Opens the ports; one sample loaned and returned leaves its memory for the first
    /// tick's loan ([`crate::recycled`]), so sending allocates nothing from the first tick on.
    pub fn open(node: &Node<Ipc>, cell: &str) -> Result<Self> {
        let setpoint = publisher(node, cell, "setpoint")?;
        drop(
            setpoint
                .loan_uninit()
                .map_err(|e| IpcError::new("loan", e))?,
        );
        Ok(CellPorts {
            setpoint,
            ready: event(node, cell)?
                .notifier_builder()
                .create()
                .map_err(|e| IpcError::new(format!("notifier of prf/{cell}/setpoint-ready"), e))?,
            joint_state: subscriber(node, cell, "joint-state")?,
        })
    }

    /// Connects the ports to the peers present now (iceoryx2 otherwise connects lazily, with
    /// allocations, on the first send or receive); call before a real-time loop.
    pub fn connect(&self) -> Result<()> {
        use iceoryx2::port::update_connections::UpdateConnections;
        let fail = |what: &str, e| IpcError::new(format!("connect the {what}"), e);
        self.setpoint
            .update_connections()
            .map_err(|e| fail("setpoint publisher", e))?;
        self.ready
            .update_connections()
            .map_err(|e| fail("setpoint-ready notifier", e))?;
        self.joint_state
            .update_connections()
            .map_err(|e| fail("joint-state subscriber", e))
    }

    /// Sends one setpoint and wakes the controller.
    pub fn send(&self, msg: SetpointMsg) -> Result<()> {
        send(&self.setpoint, msg)?;
        self.ready
            .notify()
            .map_err(|e| IpcError::new("notify", e))?;
        Ok(())
    }

    /// The newest joint state received since the last call, if any.
    pub fn newest(&self) -> Result<Option<JointStateMsg>> {
        let mut newest = None;
        drain(&self.joint_state, |m| newest = Some(m))?;
        Ok(newest)
    }
}

/// The controller's ports: reads setpoints (woken by the event), publishes joint states.
pub struct ControllerPorts {
    pub setpoint: Subscriber<Ipc, SetpointMsg, ()>,
    pub ready: Listener<Ipc>,
    pub joint_state: Publisher<Ipc, JointStateMsg, ()>,
}

impl ControllerPorts {
    pub fn open(node: &Node<Ipc>, cell: &str) -> Result<Self> {
        Ok(ControllerPorts {
            setpoint: subscriber(node, cell, "setpoint")?,
            ready: event(node, cell)?
                .listener_builder()
                .create()
                .map_err(|e| IpcError::new(format!("listener of prf/{cell}/setpoint-ready"), e))?,
            joint_state: publisher(node, cell, "joint-state")?,
        })
    }

    pub fn publish(&self, msg: JointStateMsg) -> Result<()> {
        send(&self.joint_state, msg)
    }
}

/// A passive observer of both topics (tests, tools): it sees every message, it sends none.
pub struct Observer {
    pub setpoint: Subscriber<Ipc, SetpointMsg, ()>,
    pub joint_state: Subscriber<Ipc, JointStateMsg, ()>,
}

impl Observer {
    pub fn open(node: &Node<Ipc>, cell: &str) -> Result<Self> {
        Ok(Observer {
            setpoint: subscriber(node, cell, "setpoint")?,
            joint_state: subscriber(node, cell, "joint-state")?,
        })
    }

    /// Moves every message received since the last call into the two lists.
    pub fn drain(&self, sp: &mut Vec<SetpointMsg>, js: &mut Vec<JointStateMsg>) -> Result<()> {
        drain(&self.setpoint, |m| sp.push(m))?;
        drain(&self.joint_state, |m| js.push(m))
    }
}
