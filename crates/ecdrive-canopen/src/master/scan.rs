//! Scanning a node's identity.

use super::*;

impl<T: CanTransport> Master<T> {
    /// Ask every node in `ids` for 1000h at once and collect the answers for `window_us`:
    /// the nodes that answer (with a value or an abort) exist. Returns them with 1000h.
    pub fn probe(
        &mut self,
        ids: impl IntoIterator<Item = u8>,
        window_us: u64,
    ) -> Result<Vec<(u8, Option<u32>)>, CanError> {
        let ids: Vec<u8> = ids.into_iter().filter(|n| (1..=127).contains(n)).collect();
        self.scan_replies = Some(Vec::new());
        let req = SdoRequest::initiate_upload(ObjectAddress::new(0x1000, 0));
        for &n in &ids {
            if let Err(e) = self.send(&CanFrame::from_parts(cob::sdo_rx(n), req, 8)) {
                self.scan_replies = None;
                return Err(e);
            }
            let now = self.t.now_us();
            if let Some(s) = self.slot_mut(n) {
                s.last_sdo_us = Some(now);
            }
        }
        let deadline = self.t.now_us().saturating_add(window_us);
        let r = self.pump_until(deadline, |_| false);
        let replies = self.scan_replies.take().unwrap_or_default();
        r?;
        let mut out: Vec<(u8, Option<u32>)> = Vec::new();
        for (n, data) in replies {
            if !ids.contains(&n) || out.iter().any(|(m, _)| *m == n) {
                continue;
            }
            let dt = match crate::sdo::SdoResponse::parse(&data) {
                Ok(crate::sdo::SdoResponse::UploadInitiated {
                    expedited: Some((d, 4)),
                    ..
                }) => Some(u32::from_le_bytes(d)),
                _ => None,
            };
            if let Some(s) = self.slot_mut(n) {
                s.seen = true;
            }
            out.push((n, dt));
        }
        out.sort_by_key(|(n, _)| *n);
        Ok(out)
    }
}
