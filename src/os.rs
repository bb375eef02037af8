//! Probes of the operating system (not a pipeline stage; the bottom layer beside `error`): this process's
//! CPU time and peak memory, its waited-for children's CPU time, and the memory the system can still give.
//! Linux reads `/proc` and `getrusage`; elsewhere each probe says it does not know (`None` or 0).
//!
//! Depends on nothing of the crate.

/// CPU seconds (user + system) this process has used so far, from /proc (Linux); `None` elsewhere.
pub fn process_cpu_secs() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / clock_ticks_per_sec())
}

fn clock_ticks_per_sec() -> f64 {
    // SAFETY: sysconf has no preconditions.
    let t = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
    if t > 0 { t as f64 } else { 100.0 }
}

/// CPU seconds (user + system) used by this process's waited-for children so far.
pub fn children_cpu_secs() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct we pass.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru) } != 0 {
        return 0.0;
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(ru.ru_utime) + secs(ru.ru_stime)
}

/// Peak resident set size of this process (Linux `VmHWM`), if known.
pub fn peak_memory_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Memory the system can still give this process (Linux `MemAvailable`), if known.
pub fn available_memory_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn child_cpu_time_counts_a_finished_child() {
        let before = children_cpu_secs();
        let status =
            std::process::Command::new("sh").args(["-c", "i=0; while [ $i -lt 200000 ]; do i=$((i+1)); done"]).status();
        if status.is_ok_and(|s| s.success()) {
            assert!(children_cpu_secs() > before, "a busy child used some CPU");
        }
    }

    #[test]
    fn the_probes_answer_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(process_cpu_secs().is_some_and(|s| s >= 0.0));
            assert!(peak_memory_bytes().is_some_and(|b| b > 0));
            assert!(available_memory_bytes().is_some_and(|b| b > 0));
        }
    }
}
