//! The memory limits of the process, read from /proc and /sys (Linux; what is missing
//! elsewhere is skipped), each with what is in use of it and what is kept in reserve.

use super::MIB;
use nonlin3d_solver::budget::format_bytes;

/// Address space glibc reserves for each thread's malloc arena (64 MiB on 64-bit Linux): it
/// counts against RLIMIT_AS although little of it is ever touched.
pub(super) const ARENA: u64 = if cfg!(all(target_os = "linux", target_env = "gnu")) {
    64 * MIB
} else {
    0
};

/// Kept free under every limit for what is allocated after a check (Newton's vectors, results,
/// output buffers).
pub(super) const SLACK: u64 = 32 * MIB;

/// Which limit a [`Bound`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitKind {
    /// `--max-memory`, against the resident memory in use.
    MaxMemory,
    /// The machine's available memory (`MemAvailable`).
    Available,
    /// The address-space limit (RLIMIT_AS, `ulimit -v`, `prlimit --as`), against the virtual
    /// size in use.
    AddressSpace,
    /// The cgroup's memory limit, against the cgroup's usage.
    Cgroup,
}

impl std::fmt::Display for LimitKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::MaxMemory => "--max-memory",
            Self::Available => "the memory available (MemAvailable)",
            Self::AddressSpace => "the address-space limit (RLIMIT_AS)",
            Self::Cgroup => "the cgroup's memory limit",
        })
    }
}

/// One limit: its size, what of it is in use, and what is kept in reserve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bound {
    /// Which limit.
    pub kind: LimitKind,
    /// Its size, bytes.
    pub cap: u64,
    /// Bytes of it in use now.
    pub in_use: u64,
    /// Bytes kept free (thread arenas not yet reserved, allocations after the check).
    pub reserve: u64,
}

impl Bound {
    /// Bytes left for the model.
    pub fn left(&self) -> u64 {
        self.cap
            .saturating_sub(self.in_use)
            .saturating_sub(self.reserve)
    }
}

impl std::fmt::Display for Bound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = |x: u64| format_bytes(x.into());
        write!(f, "{} of {} (", self.kind, b(self.cap))?;
        if self.in_use > 0 {
            write!(f, "{} in use, ", b(self.in_use))?;
        }
        let why = match self.kind {
            LimitKind::AddressSpace => "thread arenas, packing buffers and later allocations",
            _ => "later allocations",
        };
        write!(f, "{} kept for {why})", b(self.reserve))
    }
}

/// What the system says about memory now (Linux; `None` where a file is missing).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Readings {
    /// `MemAvailable`, bytes.
    pub mem_available: Option<u64>,
    /// The soft RLIMIT_AS, bytes (`None`: unlimited).
    pub address_space: Option<u64>,
    /// The tightest cgroup limit on the way to the root, and that cgroup's usage, bytes.
    pub cgroup: Option<(u64, u64)>,
    /// Virtual size of the process (`VmSize`), bytes.
    pub vm_size: u64,
    /// Resident size of the process (`VmRSS`), bytes.
    pub vm_rss: u64,
    /// Worker threads that allocate (rayon's pool).
    pub threads: usize,
    /// The packing buffer faer's dense kernels (private-gemm on x86-64) allocate, without a way
    /// to fail, in each thread that factors: twice the L3 cache as sysfs reads it, bytes.
    pub gemm_buffer: u64,
}

/// A sysfs cache size ("32768K", "2M"), bytes.
pub(super) fn cache_size(text: &str) -> Option<u64> {
    let t = text.trim();
    let (num, scale) = match t.chars().last()? {
        'K' => (&t[..t.len() - 1], 1024),
        'M' => (&t[..t.len() - 1], 1024 * 1024),
        _ => (t, 1),
    };
    num.parse::<u64>().ok()?.checked_mul(scale)
}

/// The value of `key` (e.g. "MemAvailable:") in a /proc text of "key value kB" lines, bytes.
pub(super) fn proc_kib(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The soft "Max address space" of a /proc/self/limits text, bytes; `None` if unlimited.
pub(super) fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// A cgroup limit file ("max", or bytes; v1 writes 2⁶³ − 4096 for none), `None` if unlimited.
pub(super) fn cgroup_limit(text: &str) -> Option<u64> {
    let v: u64 = text.trim().parse().ok()?;
    (v < 1 << 62).then_some(v)
}

/// The tightest memory limit of the cgroup at `path` and its ancestors, with that cgroup's
/// usage: v2 (`memory.max`, `memory.current`) or v1 (`memory.limit_in_bytes`,
/// `memory.usage_in_bytes`).
pub(super) fn cgroup_bound(
    root: &std::path::Path,
    path: &str,
    files: [&str; 2],
) -> Option<(u64, u64)> {
    let read = |dir: &std::path::Path, f: &str| std::fs::read_to_string(dir.join(f)).ok();
    let mut best: Option<(u64, u64)> = None;
    let mut rel = std::path::PathBuf::from(path.trim_start_matches('/'));
    loop {
        let dir = root.join(&rel);
        if let Some(cap) = read(&dir, files[0]).as_deref().and_then(cgroup_limit) {
            let used = read(&dir, files[1])
                .and_then(|t| t.trim().parse().ok())
                .unwrap_or(0);
            if best.is_none_or(|(c, _)| cap < c) {
                best = Some((cap, used));
            }
        }
        if !rel.pop() {
            break;
        }
    }
    best
}

impl Readings {
    /// Reads /proc and /sys now.
    pub fn read() -> Self {
        let text = |p: &str| std::fs::read_to_string(p).unwrap_or_default();
        let status = text("/proc/self/status");
        let cgroups = text("/proc/self/cgroup");
        let root = std::path::Path::new("/sys/fs/cgroup");
        // v2: "0::/path"; v1: "N:memory:/path" (controllers may be listed together).
        let v2 = cgroups
            .lines()
            .find_map(|l| l.strip_prefix("0::"))
            .and_then(|p| cgroup_bound(root, p, ["memory.max", "memory.current"]));
        let v1 = cgroups
            .lines()
            .filter_map(|l| l.split_once(':').and_then(|(_, rest)| rest.split_once(':')))
            .find(|(c, _)| c.split(',').any(|c| c == "memory"))
            .and_then(|(_, p)| {
                cgroup_bound(
                    &root.join("memory"),
                    p,
                    ["memory.limit_in_bytes", "memory.usage_in_bytes"],
                )
            });
        Self {
            mem_available: proc_kib(&text("/proc/meminfo"), "MemAvailable:"),
            address_space: address_space_limit(&text("/proc/self/limits")),
            cgroup: match (v2, v1) {
                (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                (a, b) => a.or(b),
            },
            vm_size: proc_kib(&status, "VmSize:").unwrap_or(0),
            vm_rss: proc_kib(&status, "VmRSS:").unwrap_or(0),
            threads: rayon::current_num_threads(),
            gemm_buffer: if cfg!(target_arch = "x86_64") {
                let l3 = text("/sys/devices/system/cpu/cpu0/cache/index3/size");
                2 * cache_size(&l3).unwrap_or(32 * MIB)
            } else {
                0
            },
        }
    }
}

/// The limits in force, each with what is left of it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Limit {
    /// Every limit found.
    pub bounds: Vec<Bound>,
}

impl Limit {
    /// No limit at all.
    pub fn none() -> Self {
        Self::default()
    }

    /// The limits from `readings` and `--max-memory`. Under RLIMIT_AS the address space that
    /// will be reserved without being used is kept in reserve: the malloc arenas of the worker
    /// threads (64 MiB each, glibc; the main thread allocates from the brk heap) and a dense
    /// packing buffer for each of them ([`Readings::gemm_buffer`]: the split's halves factor on
    /// two threads at once, each with its own), less what of them is already there (taken as
    /// the address space not resident, VmSize − VmRSS). One buffer was counted before: on a
    /// machine whose L3 reads 260 MiB (520 MiB a buffer) the thesis mesh under a 1 GiB limit
    /// passed the check and died with SIGABRT in the second half's kernel.
    pub fn from_readings(max_memory: Option<u64>, r: &Readings) -> Self {
        let mut bounds = Vec::new();
        let bound = |kind, cap, in_use, reserve| Bound {
            kind,
            cap,
            in_use,
            reserve: reserve + SLACK,
        };
        if let Some(cap) = max_memory {
            bounds.push(bound(LimitKind::MaxMemory, cap, r.vm_rss, 0));
        }
        if let Some(cap) = r.mem_available {
            bounds.push(bound(LimitKind::Available, cap, 0, 0));
        }
        if let Some(cap) = r.address_space {
            let arenas = (ARENA + r.gemm_buffer) * r.threads.max(1) as u64;
            let reserved = r.vm_size.saturating_sub(r.vm_rss);
            bounds.push(bound(
                LimitKind::AddressSpace,
                cap,
                r.vm_size,
                arenas.saturating_sub(reserved),
            ));
        }
        if let Some((cap, used)) = r.cgroup {
            bounds.push(bound(LimitKind::Cgroup, cap, used, 0));
        }
        Self { bounds }
    }

    /// The limit that leaves the least.
    pub fn tightest(&self) -> Option<&Bound> {
        self.bounds.iter().min_by_key(|b| b.left())
    }

    /// Bytes left under the tightest limit (`None`: no limit known).
    pub fn left(&self) -> Option<u64> {
        self.tightest().map(Bound::left)
    }
}
