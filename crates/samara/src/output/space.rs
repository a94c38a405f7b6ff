//! The space a results file will need, checked before an analysis runs against the free
//! space of its disk (or the available memory, for results kept in memory), so that a run
//! whose records cannot fit is known at its start and not hours later at a full disk or
//! an out-of-memory kill.

use std::fmt;
use std::path::Path;

/// Where a results file's bytes go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// A file on a disk.
    Disk,
    /// Memory ([`super::ResultsFile::in_memory`]).
    Memory,
}

/// A results file projected to outgrow the space left where it is written.
#[derive(Clone, Debug, PartialEq)]
pub struct SpaceShortfall {
    /// Where the bytes go.
    pub storage: Storage,
    /// The fewest output times the analysis writes ([`crate::model::AnalysisDef::min_records`]).
    pub records: u64,
    /// Bytes of one output time.
    pub record_bytes: u64,
    /// Bytes of the file with `records` output times (a lower bound).
    pub needed: u64,
    /// Bytes available: to the user on the file's disk, or memory the system can give
    /// without swapping.
    pub available: u64,
}

impl SpaceShortfall {
    /// `Some` when `needed` exceeds `available`.
    pub fn compare(
        storage: Storage,
        records: u64,
        record_bytes: u64,
        needed: u64,
        available: u64,
    ) -> Option<Self> {
        (needed > available).then_some(Self {
            storage,
            records,
            record_bytes,
            needed,
            available,
        })
    }

    /// What to change, for the message's hint.
    pub fn hint(&self) -> &'static str {
        match self.storage {
            Storage::Disk => {
                "record fewer output times (`output_interval`, `output_every`; fewer \
                 `load_steps` in statics), shorten the analysis, or write the results to a \
                 larger disk with --out (Python: out=DIR)"
            }
            Storage::Memory => {
                "record fewer output times (`output_interval`, `output_every`; fewer \
                 `load_steps` in statics), shorten the analysis, or write the results to a \
                 folder (Python: out=DIR)"
            }
        }
    }
}

impl fmt::Display for SpaceShortfall {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the results need at least {} ({} output times of {}), but only {} {}",
            Bytes(self.needed),
            Grouped(self.records),
            Bytes(self.record_bytes),
            Bytes(self.available),
            match self.storage {
                Storage::Disk => "are free on their disk",
                Storage::Memory => "of memory are available to hold them",
            }
        )
    }
}

/// The least size of an analysis's results, projected before it runs
/// ([`super::ResultsFile::projection`]): `samara check` prints it and compares it with
/// the free space of the results folder's disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResultsProjection {
    /// The fewest output times the analysis writes ([`crate::model::AnalysisDef::min_records`]).
    pub records: u64,
    /// Bytes of one output time.
    pub record_bytes: u64,
    /// Bytes of the file with `records` output times: its header and fixed variables
    /// included, a lower bound.
    pub bytes: u64,
}

impl ResultsProjection {
    /// The shortfall of writing these results into the folder `dir` (which need not exist
    /// yet: the free space is that of its nearest existing ancestor's disk); `None` when
    /// they fit or the system does not say.
    pub fn shortfall_in(&self, dir: &Path) -> Option<SpaceShortfall> {
        // A relative path's last ancestor is the empty path: the working folder.
        let existing = dir
            .ancestors()
            .map(|p| {
                if p.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    p
                }
            })
            .find(|p| p.exists())?;
        SpaceShortfall::compare(
            Storage::Disk,
            self.records,
            self.record_bytes,
            self.bytes,
            available_space(existing)?,
        )
    }
}

impl fmt::Display for ResultsProjection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "at least {} ({} bytes: {} output times of {})",
            Bytes(self.bytes),
            Grouped(self.bytes),
            Grouped(self.records),
            Bytes(self.record_bytes)
        )
    }
}

/// Bytes available to the user on the file system holding `path` (`None` when the
/// file system does not say). Zero counts as not said: it is asked after the file's
/// header was written, and some network and virtual file systems report no space at all.
pub fn available_space(path: &Path) -> Option<u64> {
    fs4::available_space(path).ok().filter(|&b| b > 0)
}

/// Memory the system can give without swapping, within the control group's limit where
/// one is set (a container's; Linux) (`None` where it does not say).
pub fn available_memory() -> Option<u64> {
    let mut sys = sysinfo::System::new();
    sys.refresh_memory();
    let host = sys.available_memory();
    let limited = sys
        .cgroup_limits()
        .map_or(host, |c| host.min(c.free_memory));
    Some(limited).filter(|&b| b > 0)
}

/// A count with its thousands grouped by commas (`7,500,000,001`).
struct Grouped(u64);

impl fmt::Display for Grouped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let digits = self.0.to_string();
        for (i, d) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i).is_multiple_of(3) {
                f.write_str(",")?;
            }
            write!(f, "{d}")?;
        }
        Ok(())
    }
}

/// A byte count in decimal units (B, kB, MB, GB, TB), three significant digits.
struct Bytes(u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 5] = ["B", "kB", "MB", "GB", "TB"];
        let mut v = self.0 as f64;
        let mut u = 0;
        while v >= 999.5 && u + 1 < UNITS.len() {
            v /= 1000.0;
            u += 1;
        }
        if u == 0 {
            write!(f, "{} B", self.0)
        } else {
            let digits = if v >= 99.95 {
                0
            } else if v >= 9.995 {
                1
            } else {
                2
            };
            write!(f, "{v:.digits$} {}", UNITS[u])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_grouped_by_thousands() {
        let g = |n: u64| Grouped(n).to_string();
        assert_eq!(g(0), "0");
        assert_eq!(g(999), "999");
        assert_eq!(g(1_000), "1,000");
        assert_eq!(g(7_500_000_001), "7,500,000,001");
        assert_eq!(g(u64::MAX), "18,446,744,073,709,551,615");
    }

    #[test]
    fn byte_counts_read_in_decimal_units() {
        let s = |b: u64| Bytes(b).to_string();
        assert_eq!(s(0), "0 B");
        assert_eq!(s(999), "999 B");
        assert_eq!(s(1000), "1.00 kB");
        assert_eq!(s(98_304), "98.3 kB");
        assert_eq!(s(75_100_000_000), "75.1 GB");
        assert_eq!(s(999_999_999), "1.00 GB");
        assert_eq!(s(u64::MAX), "18446744 TB");
    }

    #[test]
    fn a_shortfall_only_when_the_file_outgrows_the_space() {
        assert_eq!(
            SpaceShortfall::compare(Storage::Disk, 10, 100, 1_000, 1_000),
            None
        );
        let s = SpaceShortfall::compare(
            Storage::Disk,
            1_000_001,
            98_304,
            98_304_098_304,
            75_100_000_000,
        )
        .expect("98.3 GB does not fit in 75.1 GB");
        assert_eq!(
            s.to_string(),
            "the results need at least 98.3 GB (1,000,001 output times of 98.3 kB), but only \
             75.1 GB are free on their disk"
        );
        assert!(s.hint().contains("--out"));
        let m = SpaceShortfall::compare(Storage::Memory, 11, 1_000, 11_000, 8_000)
            .expect("11 kB do not fit in 8 kB");
        assert_eq!(
            m.to_string(),
            "the results need at least 11.0 kB (11 output times of 1.00 kB), but only \
             8.00 kB of memory are available to hold them"
        );
        assert!(m.hint().contains("out=DIR"));
    }

    #[test]
    fn a_projection_reads_in_units_and_is_compared_with_the_nearest_existing_folder() {
        let p = ResultsProjection {
            records: 1_000_001,
            record_bytes: 320,
            bytes: 320_004_096,
        };
        assert_eq!(
            p.to_string(),
            "at least 320 MB (320,004,096 bytes: 1,000,001 output times of 320 B)"
        );
        // A folder not made yet is judged by the disk of the folder it will be made in.
        let dir = std::env::temp_dir().join("samara-not-made-yet").join("out");
        assert!(!dir.exists());
        assert_eq!(
            p.shortfall_in(&dir),
            None,
            "320 MB fit in the temporary folder"
        );
        let huge = ResultsProjection {
            records: u64::MAX / 320,
            record_bytes: 320,
            bytes: u64::MAX,
        };
        let s = huge.shortfall_in(&dir).expect("18 EB do not fit");
        assert_eq!((s.storage, s.needed), (Storage::Disk, u64::MAX));
        assert!(s.available > 0 && s.available < u64::MAX);
        // A relative folder none of whose parents exists is made in the working folder.
        let relative = Path::new("samara-not-made-yet").join("out");
        assert!(!relative.exists());
        assert!(huge.shortfall_in(&relative).is_some());
        assert_eq!(p.shortfall_in(&relative), None);
    }

    #[test]
    fn this_machine_reports_its_memory_and_disk() {
        // Linux, the platform the suite runs on, reports both.
        let memory = available_memory();
        let dir = std::env::temp_dir();
        let disk = available_space(&dir);
        println!("available: memory {memory:?} B, disk {disk:?} B");
        assert!(memory.is_some_and(|b| b > 1 << 20));
        assert!(disk.is_some_and(|b| b > 0));
    }
}
