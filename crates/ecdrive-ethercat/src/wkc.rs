//! The working counter each logical datagram of the cycle must show, derived from the mapping.
//!
//! An ESC adds to the working counter of a logical datagram (LRD/LWR/LRW) when the datagram
//! touches one of its active FMMUs: +1 for a successful read (inputs), +2 for a successful
//! LRW write (outputs, +1 for LWR), once per ESC whatever the number of FMMUs it hits
//! (ETG.1000.4 §5.4.3; see the slave's `esc/fmmu.rs`). A process image larger than one frame
//! goes out as several datagrams, and one device's inputs or outputs may be cut between two:
//! that device then counts in both. So the expected value depends on where the datagrams
//! start and end, and the only sound check is per datagram.
//!
//! [`WkcPlan`] holds each device's logical ranges as the master configured them (the FMMU
//! blocks it sent, recorded by the pump's tap) and gives the expected working counter of any
//! logical datagram, without allocation. The cycle checks each datagram of a reply against it
//! and names the first one that is wrong, with the devices it covers.

use crate::ec::register::FmmuConfig;
use core::ops::Range;

/// One device's part of the logical process image.
#[derive(Debug, Clone, PartialEq, Eq)]
struct DeviceImage {
    position: u16,
    /// Logical ranges of the device's read FMMUs (its inputs).
    reads: Vec<Range<u32>>,
    /// Logical ranges of the device's write FMMUs (its outputs).
    writes: Vec<Range<u32>>,
}

fn overlaps(ranges: &[Range<u32>], a: &Range<u32>) -> bool {
    ranges.iter().any(|r| r.start < a.end && a.start < r.end)
}

/// What one logical datagram should come back with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Expected {
    /// The working counter (for LRW: +1 per device whose inputs it touches, +2 per device
    /// whose outputs it touches).
    pub wkc: u16,
    /// Lowest and highest position of the devices it touches (`None`: none).
    pub devices: Option<(u16, u16)>,
}

pub use crate::ec::DatagramWkc;

/// The expected working counters of the logical process image: each device's logical ranges as
/// the master configured them (the FMMU blocks it sent), and the count any logical datagram
/// should come back with. An ESC adds +1 when a datagram touches its inputs, +2 (LRW) when it
/// touches its outputs, once per ESC; a device cut between two datagrams counts in both.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct WkcPlan {
    devices: Vec<DeviceImage>,
    /// The expected counts of the datagrams that repeat every cycle, found without walking
    /// the devices ([`remember`](Self::remember)).
    memo: Vec<(u32, u16, Expected)>,
}

impl WkcPlan {
    /// The plan for the devices `(position, station address)` from the FMMU blocks sent to
    /// them `(station address, FMMU number, block)`: active blocks with a length count, by
    /// their read/write type. Devices without such a block do not take part.
    pub fn from_fmmus(
        devices: impl IntoIterator<Item = (u16, u16)>,
        fmmus: impl IntoIterator<Item = (u16, u8, FmmuConfig)>,
    ) -> Self {
        let fmmus: Vec<(u16, u8, FmmuConfig)> = fmmus.into_iter().collect();
        let mut out: Vec<DeviceImage> = devices
            .into_iter()
            .map(|(position, address)| {
                let mut blocks: Vec<(u8, FmmuConfig)> = fmmus
                    .iter()
                    .filter(|(st, _, c)| *st == address && c.active && c.length > 0)
                    .map(|&(_, n, c)| (n, c))
                    .collect();
                blocks.sort_by_key(|(n, _)| *n);
                let range = |want: fn(&FmmuConfig) -> bool| {
                    blocks
                        .iter()
                        .filter(|(_, c)| want(c))
                        .map(|(_, c)| c.logical_range())
                        .collect::<Vec<_>>()
                };
                DeviceImage {
                    position,
                    reads: range(|c| c.read),
                    writes: range(|c| c.write),
                }
            })
            .filter(|d| !d.reads.is_empty() || !d.writes.is_empty())
            .collect();
        out.sort_by_key(|d| d.position);
        Self {
            devices: out,
            memo: Vec::new(),
        }
    }

    /// Remember what the logical datagrams `(address, len)` should come back with: the
    /// cycle's own, which go out every cycle. [`expected`](Self::expected) then looks them up
    /// instead of walking every device's ranges.
    pub fn remember(&mut self, datagrams: impl IntoIterator<Item = (u32, u16)>) {
        let memo: Vec<(u32, u16, Expected)> = datagrams
            .into_iter()
            .map(|(a, l)| (a, l, self.walk(a, l)))
            .collect();
        self.memo = memo;
    }

    /// Whether any device takes part.
    pub fn is_empty(&self) -> bool {
        self.devices.is_empty()
    }

    /// The working counter an LRW covering the whole image shows: 2 per device with outputs
    /// plus 1 per device with inputs.
    pub fn whole(&self) -> u16 {
        self.devices
            .iter()
            .map(|d| u16::from(!d.reads.is_empty()) + 2 * u16::from(!d.writes.is_empty()))
            .sum()
    }

    /// What an LRW at logical `address` of `len` bytes should come back with. No allocation.
    pub fn expected(&self, address: u32, len: u16) -> Expected {
        match self.memo.iter().find(|m| m.0 == address && m.1 == len) {
            Some(&(_, _, e)) => e,
            None => self.walk(address, len),
        }
    }

    /// [`expected`](Self::expected), from every device's ranges.
    fn walk(&self, address: u32, len: u16) -> Expected {
        let span = address..address.saturating_add(u32::from(len));
        let mut e = Expected::default();
        for d in &self.devices {
            let r = overlaps(&d.reads, &span);
            let w = overlaps(&d.writes, &span);
            if !(r || w) {
                continue;
            }
            e.wkc += u16::from(r) + 2 * u16::from(w);
            e.devices = Some(match e.devices {
                None => (d.position, d.position),
                Some((lo, hi)) => (lo.min(d.position), hi.max(d.position)),
            });
        }
        e
    }

    /// Check the logical datagrams `(address, len, wkc)` of one reply, in order: the total
    /// expected, and the first datagram whose working counter is wrong (`None`: all right).
    /// No allocation.
    pub fn check(
        &self,
        datagrams: impl ExactSizeIterator<Item = (u32, u16, u16)>,
    ) -> (u16, Option<DatagramWkc>) {
        let of = u8::try_from(datagrams.len()).unwrap_or(u8::MAX);
        let mut total = 0u16;
        let mut wrong = None;
        for (i, (address, len, got)) in datagrams.enumerate() {
            let e = self.expected(address, len);
            total = total.saturating_add(e.wkc);
            if got != e.wkc && wrong.is_none() {
                wrong = Some(DatagramWkc {
                    index: u8::try_from(i + 1).unwrap_or(u8::MAX),
                    of,
                    address,
                    len,
                    got,
                    expected: e.wkc,
                    devices: e.devices,
                });
            }
        }
        (total, wrong)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(start: u32, len: u16, read: bool) -> FmmuConfig {
        FmmuConfig {
            logical_start: start,
            length: len,
            logical_stop_bit: 7,
            physical_start: 0x1000,
            read,
            write: !read,
            active: true,
            ..FmmuConfig::default()
        }
    }

    /// The layout ethercrab 0.7.1 gives a group: every device's inputs first, then every
    /// device's outputs, without gaps (`SubDeviceGroup::configure_fmmus`).
    fn plan(sizes: &[(u16, u16)]) -> WkcPlan {
        let mut fmmus = Vec::new();
        let mut at = 0u32;
        for (i, &(_, inp)) in sizes.iter().enumerate() {
            if inp > 0 {
                fmmus.push((0x1000 + i as u16, 1, block(at, inp, true)));
                at += u32::from(inp);
            }
        }
        for (i, &(out, _)) in sizes.iter().enumerate() {
            if out > 0 {
                fmmus.push((0x1000 + i as u16, 0, block(at, out, false)));
                at += u32::from(out);
            }
        }
        WkcPlan::from_fmmus((0..sizes.len() as u16).map(|p| (p, 0x1000 + p)), fmmus)
    }

    /// ethercrab 0.7.1's cut of the image over frames of 1514 bytes with DC: the first LRW
    /// carries 1466 bytes (after the 20-byte FRMW of the system time), the others 1486.
    fn chunks(total: u32) -> Vec<(u32, u16)> {
        let mut out = Vec::new();
        let mut at = 0;
        let mut cap = 1466;
        while at < total {
            let n = cap.min(total - at);
            out.push((at, n as u16));
            at += n;
            cap = 1486;
        }
        out
    }

    fn expected_sum(p: &WkcPlan, sizes: &[(u16, u16)]) -> u16 {
        let total: u32 = sizes
            .iter()
            .map(|&(o, i)| u32::from(o) + u32::from(i))
            .sum();
        chunks(total)
            .iter()
            .map(|&(a, l)| p.expected(a, l).wkc)
            .sum()
    }

    // Default cyclic mappings: MR-J4-TM 13 bytes out / 21 in, BDHDE 13 / 19.
    fn mix(n: usize) -> Vec<(u16, u16)> {
        (0..n)
            .map(|i| if i % 2 == 0 { (13, 21) } else { (13, 19) })
            .collect()
    }

    #[test]
    fn one_datagram_counts_three_per_drive() {
        let s = mix(40);
        let p = plan(&s);
        assert_eq!(p.whole(), 120);
        assert_eq!(chunks(20 * 34 + 20 * 32).len(), 1);
        assert_eq!(expected_sum(&p, &s), 120);
    }

    #[test]
    fn a_drive_cut_between_two_datagrams_counts_in_both() {
        // The figures of the scale report: 48 drives 146 against 144, 64 drives 194 against 192,
        // 128 devices of 6/6 bytes 386 against 384.
        for (sizes, whole, split) in [
            (mix(48), 144, 146),
            (mix(64), 192, 194),
            (vec![(6u16, 6u16); 128], 384, 386),
        ] {
            let p = plan(&sizes);
            assert_eq!(p.whole(), whole);
            assert_eq!(expected_sum(&p, &sizes), split, "{} devices", sizes.len());
        }
    }

    #[test]
    fn check_names_the_wrong_datagram_and_its_devices() {
        let s = mix(48);
        let p = plan(&s);
        let c = chunks(1584);
        let good: Vec<(u32, u16, u16)> = c
            .iter()
            .map(|&(a, l)| (a, l, p.expected(a, l).wkc))
            .collect();
        assert_eq!(p.check(good.iter().copied()), (146, None));
        // The second datagram (outputs of drives 38..47) loses one device's write.
        let mut bad = good.clone();
        bad[1].2 -= 2;
        let (total, wrong) = p.check(bad.iter().copied());
        assert_eq!(total, 146);
        let w = wrong.unwrap();
        assert_eq!((w.index, w.of, w.address, w.len), (2, 2, 1466, 118));
        assert_eq!((w.got, w.expected), (18, 20));
        assert_eq!(w.devices, Some((38, 47)));
    }

    #[test]
    fn remembered_datagrams_count_as_walked_ones() {
        let s = mix(48);
        let walked = plan(&s);
        let mut remembered = walked.clone();
        let c = chunks(1584);
        remembered.remember(c.iter().copied());
        for &(a, l) in &c {
            assert_eq!(remembered.expected(a, l), walked.expected(a, l));
        }
        // A datagram not remembered is walked.
        assert_eq!(remembered.expected(0, 34), walked.expected(0, 34));
        // The inputs of drives 0 (21 bytes) and 1 (19 bytes from byte 21).
        assert_eq!(remembered.expected(0, 34).wkc, 2);
    }

    #[test]
    fn inactive_or_empty_blocks_and_other_stations_do_not_count() {
        let mut off = block(0, 4, true);
        off.active = false;
        let fmmus = [
            (0x1000, 0, off),
            (0x1000, 1, block(0, 0, true)),
            (0x1001, 0, block(0, 4, true)),
            (0x2000, 0, block(0, 4, false)),
        ];
        let p = WkcPlan::from_fmmus([(0, 0x1000), (1, 0x1001)], fmmus);
        assert_eq!(p.whole(), 1);
        assert_eq!(p.expected(0, 4).devices, Some((1, 1)));
        assert_eq!(p.expected(4, 4), Expected::default());
    }
}
