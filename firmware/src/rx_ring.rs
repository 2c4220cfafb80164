//! A receive queue: a ring of bytes that an interrupt handler fills ([`RxProducer`]) and the
//! main loop empties ([`RxConsumer`]), reading the bytes waiting where they lie, a run at a
//! time ([`RxConsumer::waiting`]), so that a line's characters go into its line in one step
//! instead of one call per byte. One producer and one consumer, on one core: each side owns
//! its end's position (bytes ever written, bytes ever read: wrapping counts) and only reads
//! the other's, so no lock is needed. Holds `N - 1` bytes (`N` a power of two).
//!
//! One core: the producer is an interrupt handler that preempts the consumer, never runs
//! beside it, so ordering the accesses in the compiler (`compiler_fence`) is enough; the
//! M0+'s `dmb` that atomic acquire and release would add costs cycles on every byte.

use core::{
    cell::UnsafeCell,
    sync::atomic::{compiler_fence, AtomicUsize, Ordering},
};

/// The ring; split once into its two ends ([`RxRing::split`]).
pub struct RxRing<const N: usize> {
    bytes: UnsafeCell<[u8; N]>,
    /// Bytes ever written (wrapping): only the producer stores it.
    written: AtomicUsize,
    /// Bytes ever read (wrapping): only the consumer stores it.
    read: AtomicUsize,
}

// SAFETY: the two ends touch disjoint bytes: the producer writes only at `written`, outside
// the bytes waiting (`read..written`), and publishes them by storing `written` (Release) after;
// the consumer reads only bytes waiting, and frees them by storing `read` after. (Both ends
// run on one core, the producer in an interrupt: a compiler fence orders each end's accesses.)
unsafe impl<const N: usize> Sync for RxRing<N> {}

impl<const N: usize> RxRing<N> {
    const SIZE_IS_A_POWER_OF_TWO: () = assert!(N.is_power_of_two());

    pub const fn new() -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::SIZE_IS_A_POWER_OF_TWO;
        RxRing {
            bytes: UnsafeCell::new([0; N]),
            written: AtomicUsize::new(0),
            read: AtomicUsize::new(0),
        }
    }

    /// The two ends (the `&'static mut` makes it once per ring).
    pub fn split(&'static mut self) -> (RxProducer<N>, RxConsumer<N>) {
        let ring: &'static RxRing<N> = self;
        (RxProducer { ring }, RxConsumer { ring })
    }
}

/// The interrupt handler's end.
pub struct RxProducer<const N: usize> {
    ring: &'static RxRing<N>,
}

impl<const N: usize> RxProducer<N> {
    /// Room for how many more bytes: the ring's free bytes (the consumer only adds to them, and
    /// not while the producer runs: it is an interrupt handler on the same core).
    #[inline]
    pub fn room(&self) -> usize {
        let written = self.ring.written.load(Ordering::Relaxed);
        let read = self.ring.read.load(Ordering::Relaxed);
        (N - 1) - written.wrapping_sub(read)
    }

    /// Writes `byte` `offset` bytes after the last byte published, not published yet (the
    /// consumer does not see it): straight from a FIFO into the ring, no buffer between. The
    /// caller keeps `offset` below [`RxProducer::room`] and publishes what it staged with
    /// [`RxProducer::publish`].
    #[inline]
    pub fn stage(&mut self, offset: usize, byte: u8) {
        let written = self.ring.written.load(Ordering::Relaxed);
        let base = self.ring.bytes.get() as *mut u8;
        // SAFETY: `offset` is below the room (the caller's rule), so this index is not among
        // the bytes waiting, which the consumer alone reads until `written` passes it.
        unsafe { base.add(written.wrapping_add(offset) % N).write(byte) };
    }

    /// Hands the `count` bytes staged (offsets `0..count`) to the consumer, in order.
    #[inline]
    pub fn publish(&mut self, count: usize) {
        let written = self.ring.written.load(Ordering::Relaxed);
        compiler_fence(Ordering::Release);
        self.ring
            .written
            .store(written.wrapping_add(count), Ordering::Relaxed);
    }
}

/// The main loop's end.
pub struct RxConsumer<const N: usize> {
    ring: &'static RxRing<N>,
}

impl<const N: usize> RxConsumer<N> {
    /// The bytes waiting, oldest first, as far as they lie in one piece (the rest, after the
    /// ring's end, come as the next run once these are [`RxConsumer::consume`]d).
    #[inline]
    pub fn waiting(&self) -> &[u8] {
        let read = self.ring.read.load(Ordering::Relaxed);
        let written = self.ring.written.load(Ordering::Relaxed);
        compiler_fence(Ordering::Acquire);
        let start = read % N;
        let len = written.wrapping_sub(read).min(N - start);
        // SAFETY: `start..start + len` lies in the ring and holds bytes published by the
        // producer, which writes none of them again before `read` passes them (consume takes
        // `&mut self`, so not while this borrow lives).
        unsafe { core::slice::from_raw_parts((self.ring.bytes.get() as *const u8).add(start), len) }
    }

    /// Frees the first `count` bytes of [`RxConsumer::waiting`] (at most as many as it held).
    #[inline]
    pub fn consume(&mut self, count: usize) {
        let read = self.ring.read.load(Ordering::Relaxed);
        compiler_fence(Ordering::Release);
        self.ring
            .read
            .store(read.wrapping_add(count), Ordering::Relaxed);
    }

    /// The next byte, taken; `None` if nothing waits.
    #[inline]
    pub fn dequeue(&mut self) -> Option<u8> {
        let byte = *self.waiting().first()?;
        self.consume(1);
        Some(byte)
    }

    /// Something waits.
    #[inline]
    pub fn ready(&self) -> bool {
        self.ring.written.load(Ordering::Relaxed) != self.ring.read.load(Ordering::Relaxed)
    }
}
