//! An iceoryx2 service type that allocates nothing per sample. iceoryx2 0.10 keeps the local
//! state of every loaned sample in the service's `ArcThreadSafetyPolicy`, which for
//! `ipc::Service` is an `Rc`: one heap allocation per loan, so one per tick of the cell loop.
//! [`Service`] is `ipc::Service` with that policy replaced by [`Recycled`], a reference-counted
//! cell whose memory goes back to a small per-thread free list when its last reference is
//! dropped; the next loan takes it from there. After the first sample of each kind nothing is
//! allocated. Shared memory, naming and wire format are `ipc::Service`'s, type for type.

use core::alloc::Layout;
use core::cell::{Cell, RefCell};
use core::fmt::Debug;
use core::marker::PhantomData;
use core::ops::Deref;
use core::ptr::NonNull;
use iceoryx2::prelude::ipc;
use iceoryx2_bb_elementary_traits::testing::abandonable::Abandonable;
use iceoryx2_bb_elementary_traits::zero_copy_send::ZeroCopySend;
use iceoryx2_cal::arc_sync_policy::{ArcSyncPolicy, ArcSyncPolicyCreationError, LockGuard};

/// `ipc::Service` whose per-sample local state lives in [`Recycled`] memory.
#[derive(Debug, Clone)]
pub struct Service {}

type Ipc = ipc::Service;
use iceoryx2::service::Service as S;

impl S for Service {
    type ServiceNameHasher = <Ipc as S>::ServiceNameHasher;
    type StaticStorage = <Ipc as S>::StaticStorage;
    type ConfigSerializer = <Ipc as S>::ConfigSerializer;
    type PersistentDynamicStorage<T: Debug + Send + Sync + ZeroCopySend + 'static> =
        <Ipc as S>::PersistentDynamicStorage<T>;
    type Bag = <Ipc as S>::Bag;
    type DynamicStorage<T: Debug + Send + Sync + ZeroCopySend + 'static> =
        <Ipc as S>::DynamicStorage<T>;
    type SharedMemory = <Ipc as S>::SharedMemory;
    type ResizableSharedMemory = <Ipc as S>::ResizableSharedMemory;
    type Connection = <Ipc as S>::Connection;
    type Event = <Ipc as S>::Event;
    type Monitoring = <Ipc as S>::Monitoring;
    type Reactor = <Ipc as S>::Reactor;
    type ArcThreadSafetyPolicy<T: Send + Debug + Abandonable> = Recycled<T>;
    type BlackboardMgmt<KeyType: Send + Sync + Debug + ZeroCopySend + 'static> =
        <Ipc as S>::BlackboardMgmt<KeyType>;
    type BlackboardPayload = <Ipc as S>::BlackboardPayload;
    type UniqueId = <Ipc as S>::UniqueId;
}

// iceoryx2's hidden marker trait for service types; its methods have defaults.
impl iceoryx2::service::internal::ServiceInternal<Service> for Service {}

/// Blocks kept for reuse per thread; more are returned to the allocator.
const FREE_BLOCKS: usize = 64;

/// Memory blocks of dropped [`Recycled`] cells, by layout.
struct FreeList(Vec<(Layout, NonNull<u8>)>);

impl FreeList {
    fn take(&mut self, layout: Layout) -> Option<NonNull<u8>> {
        let i = self.0.iter().position(|(l, _)| *l == layout)?;
        Some(self.0.swap_remove(i).1)
    }

    /// Keeps `block` if there is room (never grows the list), else frees it.
    fn give(&mut self, layout: Layout, block: NonNull<u8>) {
        if self.0.len() < self.0.capacity() {
            self.0.push((layout, block));
        } else {
            // SAFETY: `block` was allocated with `layout` by `Recycled::new`.
            unsafe { std::alloc::dealloc(block.as_ptr(), layout) };
        }
    }
}

impl Drop for FreeList {
    fn drop(&mut self) {
        for (layout, block) in self.0.drain(..) {
            // SAFETY: as in `give`.
            unsafe { std::alloc::dealloc(block.as_ptr(), layout) };
        }
    }
}

thread_local! {
    static FREE: RefCell<FreeList> = RefCell::new(FreeList(Vec::with_capacity(FREE_BLOCKS)));
}

struct Inner<T> {
    refs: Cell<usize>,
    value: T,
}

/// A single-threaded reference-counted cell (like `Rc`) whose memory is recycled per thread.
pub struct Recycled<T: Send + Debug + Abandonable> {
    inner: NonNull<Inner<T>>,
    _owns: PhantomData<Inner<T>>,
}

impl<T: Send + Debug + Abandonable> Recycled<T> {
    fn inner(&self) -> &Inner<T> {
        // SAFETY: `inner` is live while any reference to it is.
        unsafe { self.inner.as_ref() }
    }

    /// Returns the memory of a cell whose value is gone (dropped or abandoned).
    fn release(inner: NonNull<Inner<T>>) {
        let layout = Layout::new::<Inner<T>>();
        let block = inner.cast::<u8>();
        let kept = FREE.try_with(|f| f.borrow_mut().give(layout, block));
        if kept.is_err() {
            // The thread's free list is gone (thread exit): back to the allocator.
            // SAFETY: allocated with `layout` by `new`.
            unsafe { std::alloc::dealloc(block.as_ptr(), layout) };
        }
    }
}

impl<T: Send + Debug + Abandonable> ArcSyncPolicy<T> for Recycled<T> {
    type LockGuard<'parent>
        = Guard<'parent, T>
    where
        Self: 'parent,
        T: 'parent;

    fn new(value: T) -> Result<Self, ArcSyncPolicyCreationError> {
        let layout = Layout::new::<Inner<T>>();
        let reused = FREE
            .try_with(|f| f.borrow_mut().take(layout))
            .ok()
            .flatten();
        let block = match reused {
            Some(b) => b,
            // SAFETY: `layout` has a non-zero size (it holds the count).
            None => NonNull::new(unsafe { std::alloc::alloc(layout) })
                .ok_or(ArcSyncPolicyCreationError::InsufficientResources)?,
        };
        let inner = block.cast::<Inner<T>>();
        // SAFETY: `block` is unused memory of `Inner<T>`'s layout.
        unsafe {
            inner.write(Inner {
                refs: Cell::new(1),
                value,
            })
        };
        Ok(Recycled {
            inner,
            _owns: PhantomData,
        })
    }

    fn lock(&self) -> Guard<'_, T> {
        Guard(&self.inner().value)
    }
}

impl<T: Send + Debug + Abandonable> Clone for Recycled<T> {
    fn clone(&self) -> Self {
        let refs = &self.inner().refs;
        refs.set(refs.get() + 1);
        Recycled {
            inner: self.inner,
            _owns: PhantomData,
        }
    }
}

impl<T: Send + Debug + Abandonable> Drop for Recycled<T> {
    fn drop(&mut self) {
        let refs = &self.inner().refs;
        refs.set(refs.get() - 1);
        if refs.get() == 0 {
            // SAFETY: the last reference: the value is dropped once, then its memory reused.
            unsafe { core::ptr::drop_in_place(&raw mut (*self.inner.as_ptr()).value) };
            Self::release(self.inner);
        }
    }
}

impl<T: Send + Debug + Abandonable> Abandonable for Recycled<T> {
    /// As iceoryx2's `Rc` policy: the last reference abandons the value, any other drops
    /// its reference.
    unsafe fn abandon_in_place(this: NonNull<Self>) {
        // SAFETY: `this` is a live `Recycled` that is not used or dropped afterwards.
        let inner = unsafe { this.as_ref() }.inner;
        // SAFETY: `inner` is live while `this` is.
        let refs = unsafe { &inner.as_ref().refs };
        if refs.get() == 1 {
            // SAFETY: the only reference; the value is not touched again.
            unsafe {
                T::abandon_in_place(NonNull::new_unchecked(&raw mut (*inner.as_ptr()).value))
            };
            Self::release(inner);
        } else {
            refs.set(refs.get() - 1);
        }
    }
}

impl<T: Send + Debug + Abandonable> Debug for Recycled<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("Recycled")
            .field(&self.inner().value)
            .finish()
    }
}

/// Access to a [`Recycled`] value (single-threaded: nothing to lock).
pub struct Guard<'parent, T>(&'parent T);

impl<T> Deref for Guard<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        self.0
    }
}

impl<'parent, T: Send + Debug + Abandonable> LockGuard<'parent, T> for Guard<'parent, T> {}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug)]
    struct Counted<'a>(&'a Cell<u32>);

    impl Drop for Counted<'_> {
        fn drop(&mut self) {
            self.0.set(self.0.get() + 1);
        }
    }

    // SAFETY (test): never sent across threads.
    unsafe impl Send for Counted<'_> {}

    impl Abandonable for Counted<'_> {
        unsafe fn abandon_in_place(_: NonNull<Self>) {}
    }

    /// The value is dropped once, when the last clone goes, and the next cell of the same
    /// layout reuses its memory; an abandoned value is not dropped.
    #[test]
    fn drops_once_reuses_memory_and_abandons_without_drop() {
        let drops = Cell::new(0);
        let a = Recycled::new(Counted(&drops)).unwrap();
        let first = a.inner.as_ptr() as usize;
        let b = a.clone();
        drop(a);
        assert_eq!(drops.get(), 0);
        assert!(core::ptr::eq(b.lock().0, &b.inner().value));
        drop(b);
        assert_eq!(drops.get(), 1);
        let c = Recycled::new(Counted(&drops)).unwrap();
        assert_eq!(c.inner.as_ptr() as usize, first, "memory reused");
        let mut c = core::mem::ManuallyDrop::new(c);
        // SAFETY: `c` is not used afterwards.
        unsafe { Recycled::abandon_in_place(NonNull::from(&mut *c)) };
        assert_eq!(drops.get(), 1, "abandoned, not dropped");
        let d = Recycled::new(Counted(&drops)).unwrap();
        assert_eq!(d.inner.as_ptr() as usize, first, "abandoned memory reused");
    }
}
