//! A criterion measurement of the benchmark thread's own CPU time, shared by the benches that
//! time single-threaded work (`raster`, `render`): on the shared 2-core machine, wall time also
//! counts the turns other processes take on the core.

use criterion::measurement::{Measurement, ValueFormatter, WallTime};

/// CPU time of the measuring thread (from `/proc/thread-self/schedstat`, in ns): the
/// single-threaded cost, less disturbed by other processes on a shared machine.
pub struct ThreadCpu;

/// The thread's CPU time so far, ns; `None` where the kernel does not report it.
pub fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = u64;

    fn start(&self) -> u64 {
        thread_cpu_ns().unwrap_or(0)
    }
    fn end(&self, start: u64) -> u64 {
        thread_cpu_ns().unwrap_or(0).saturating_sub(start)
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, value: &u64) -> f64 {
        *value as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        static WALL: WallTime = WallTime;
        WALL.formatter()
    }
}
