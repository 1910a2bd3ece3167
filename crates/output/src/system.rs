//! What the commands read of the machine and of their own process, for the memory gates and
//! the reports: the memory available, the process's peak resident memory (overall and per
//! stage of a render), its CPU time, the load average and the CPU model. All from Linux's
//! /proc; elsewhere each probe answers `None` or "unknown" and the callers go on without it.
//!
//! The one module that reads /proc, kept apart from the files the commands write: the driver
//! and the lab both read these numbers, and this crate is the lowest one they share.

use bdpm_integrator::{Stage, StageProbe};

/// MemAvailable of /proc/meminfo, bytes (`None` where there is no such file).
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The process's peak resident memory so far (VmHWM of /proc/self/status), bytes.
pub fn peak_resident_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Peak resident memory per stage of a render (Linux): as a stage starts, the kernel's
/// high-water mark VmHWM is folded into the overall peak and reset to the current resident
/// size (`/proc/self/clear_refs`, value 5); as it ends, VmHWM is that stage's peak. Where the
/// reset is not possible, no stage peaks are recorded (they would be cumulative).
#[derive(Debug, Default)]
pub struct StagePeaks {
    state: std::sync::Mutex<PeakState>,
}

#[derive(Debug, Default)]
struct PeakState {
    overall: u64,
    reset_works: Option<bool>,
    stages: Vec<(Stage, u64)>,
}

impl StagePeaks {
    /// The largest peak of each stage, bytes, in the order the stages first ended.
    pub fn stages(&self) -> Vec<(Stage, u64)> {
        self.state
            .lock()
            .map(|s| s.stages.clone())
            .unwrap_or_default()
    }

    /// The process's peak resident memory over the whole run, bytes (VmHWM now, or any
    /// earlier peak that a stage reset hid).
    pub fn overall(&self) -> Option<u64> {
        let now = peak_resident_memory()?;
        Some(self.state.lock().map_or(now, |s| s.overall.max(now)))
    }
}

impl StageProbe for StagePeaks {
    fn enter(&self, _stage: Stage) {
        let Ok(mut s) = self.state.lock() else { return };
        if let Some(peak) = peak_resident_memory() {
            s.overall = s.overall.max(peak);
        }
        let ok = std::fs::write("/proc/self/clear_refs", "5").is_ok();
        s.reset_works = Some(s.reset_works.unwrap_or(true) && ok);
    }

    fn leave(&self, stage: Stage) {
        let Ok(mut s) = self.state.lock() else { return };
        let Some(peak) = peak_resident_memory() else {
            return;
        };
        s.overall = s.overall.max(peak);
        if s.reset_works != Some(true) {
            return;
        }
        match s.stages.iter_mut().find(|(n, _)| *n == stage) {
            Some((_, p)) => *p = (*p).max(peak),
            None => s.stages.push((stage, peak)),
        }
    }
}

/// One line of /proc/loadavg (its first three fields), or "unknown".
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".into())
}

/// The CPU model from /proc/cpuinfo, or "unknown".
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// CPU time of this process so far (user + system, all threads), s; `None` where
/// /proc/self/stat is not available. Its resolution is the kernel's USER_HZ tick (10 ms).
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name, which is in parentheses and may contain spaces:
    // state is field 3, utime field 14, stime field 15 (proc(5)).
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}
