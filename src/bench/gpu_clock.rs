//! The GPU's SM clock where the driver exposes it (`nvidia-smi`), read at the start and
//! end of every benchmark point: an H200 idles at ~345 MHz and needs about a second of
//! work to reach ~1980 MHz, so a timing taken below its clock says so in the results.

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// One reading of the first GPU's clocks, MHz.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SmClock {
    pub(crate) mhz: u32,
    pub(crate) max_mhz: u32,
}

/// How long a reading may take before it is given up (a hung driver must not hang the
/// benchmark).
const TIMEOUT: Duration = Duration::from_secs(3);

/// The first GPU's current and maximum SM clock, or `None` where `nvidia-smi` is missing,
/// fails or is slow (any adapter but NVIDIA's, lavapipe).
pub(crate) fn read() -> Option<SmClock> {
    let mut child = Command::new("nvidia-smi")
        .args([
            "--query-gpu=clocks.sm,clocks.max.sm",
            "--format=csv,noheader,nounits",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) if status.success() => break,
            Ok(Some(_)) | Err(_) => return None,
            Ok(None) if start.elapsed() > TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
        }
    }
    let mut out = String::new();
    child.stdout.take()?.read_to_string(&mut out).ok()?;
    parse(&out)
}

/// The first line of `nvidia-smi`'s CSV answer: "1980, 1980".
fn parse(csv: &str) -> Option<SmClock> {
    let mut fields = csv.lines().next()?.split(',').map(str::trim);
    let mhz = fields.next()?.parse().ok()?;
    let max_mhz = fields.next()?.parse().ok()?;
    Some(SmClock { mhz, max_mhz })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_first_gpu() {
        assert_eq!(
            parse("345, 1980\n1980, 1980\n"),
            Some(SmClock {
                mhz: 345,
                max_mhz: 1980
            })
        );
        assert_eq!(parse("[N/A], 1980\n"), None);
        assert_eq!(parse(""), None);
    }
}
