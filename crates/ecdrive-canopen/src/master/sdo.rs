//! SDO: the paced client (expedited and segmented transfers) and typed values.

use super::*;

impl<T: CanTransport> Master<T> {
    pub(super) fn sdo_interval(&self, node: u8) -> u64 {
        let s = self.slot(node);
        let v = s
            .and_then(|s| s.sdo_interval_override)
            .or_else(|| {
                s.and_then(|s| s.profile)
                    .map(|p| p.comm.sdo_min_interval_us)
            })
            .unwrap_or(self.cfg.unknown_sdo_interval_us);
        u64::from(v)
    }

    /// Send one SDO request to `node` at the earliest time its pacing allows.
    pub(super) fn send_sdo(&mut self, node: u8, req: [u8; 8]) -> Result<(), CanError> {
        let min = self.sdo_interval(node);
        if let Some(last) = self.slot(node).and_then(|s| s.last_sdo_us) {
            let ready = last.saturating_add(min);
            if self.t.now_us() < ready {
                self.pump_until(ready, |_| false)?;
            }
        }
        let now = self.t.now_us();
        if let Some(s) = self.slot_mut(node) {
            s.last_sdo_us = Some(now);
        }
        self.send(&CanFrame::from_parts(cob::sdo_rx(node), req, 8))
    }

    pub(super) fn sdo_exchange(
        &mut self,
        node: u8,
        req: [u8; 8],
    ) -> Result<Option<[u8; 8]>, CanError> {
        self.send_sdo(node, req)?;
        self.sdo_wait = Some(node);
        self.sdo_reply = None;
        let deadline = self.t.now_us().saturating_add(self.cfg.sdo_timeout_us);
        let r = self.pump_until(deadline, |m| m.sdo_reply.is_some());
        self.sdo_wait = None;
        r?;
        Ok(self.sdo_reply.take())
    }

    pub(super) fn run_transfer(
        &mut self,
        node: u8,
        mut t: ClientTransfer,
        first: [u8; 8],
    ) -> Result<Option<Vec<u8>>, CanError> {
        let addr = t.address();
        let mut req = first;
        loop {
            let Some(resp) = self.sdo_exchange(node, req)? else {
                let _ = self.send_sdo(node, t.abort());
                return Err(self.err(
                    node,
                    Some(addr),
                    CanErrorKind::Sdo(SdoError::Timeout(self.cfg.sdo_timeout_us / 1000)),
                ));
            };
            match t.on_response(&resp) {
                Ok(ClientStep::Send(next)) => req = next,
                Ok(ClientStep::Uploaded(v)) => return Ok(Some(v)),
                Ok(ClientStep::Downloaded) => return Ok(None),
                Err(SdoError::Abort(code)) => {
                    let text = match self.profile(node) {
                        Some(p) => p.abort_text(code),
                        None => crate::sdo::abort_text(code, &[]),
                    };
                    return Err(self.err(node, Some(addr), CanErrorKind::Abort(text)));
                }
                Err(e) => {
                    if matches!(e, SdoError::Protocol { .. } | SdoError::TooLarge(_)) {
                        let _ = self.send_sdo(node, t.abort());
                    }
                    return Err(self.err(node, Some(addr), CanErrorKind::Sdo(e)));
                }
            }
        }
    }

    /// Upload (read) `addr` from `node`: the raw little-endian bytes.
    pub fn sdo_upload(&mut self, node: u8, addr: ObjectAddress) -> Result<Vec<u8>, CanError> {
        self.check_node(node)?;
        let (t, first) = ClientTransfer::upload(addr);
        Ok(self.run_transfer(node, t, first)?.unwrap_or_default())
    }

    /// Download (write) `data` to `addr` of `node`: expedited up to 4 bytes, segmented above.
    pub fn sdo_download(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        data: &[u8],
    ) -> Result<(), CanError> {
        self.check_node(node)?;
        let (t, first) = ClientTransfer::download(addr, data.to_vec())
            .map_err(|e| self.err(node, Some(addr), CanErrorKind::Sdo(e)))?;
        self.run_transfer(node, t, first).map(|_| ())
    }

    /// Download `data` to `addr` of `node` with the segmented protocol even if it would fit an
    /// expedited transfer.
    pub fn sdo_download_segmented(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        data: &[u8],
    ) -> Result<(), CanError> {
        self.check_node(node)?;
        let (t, first) = ClientTransfer::download_segmented(addr, data.to_vec())
            .map_err(|e| self.err(node, Some(addr), CanErrorKind::Sdo(e)))?;
        self.run_transfer(node, t, first).map(|_| ())
    }

    /// The data type of `addr` on `node` from its profile's dictionary, or `given`.
    pub fn data_type(
        &self,
        node: u8,
        addr: ObjectAddress,
        given: Option<DataType>,
    ) -> Result<DataType, CanError> {
        if let Some(dt) = given {
            return Ok(dt);
        }
        // The node's profile; for a node without one (served from an EDS file, a drive
        // ecdrive has no profile for) the type CiA 301/402 give the object.
        self.profile(node)
            .and_then(|p| Dictionary::new(p.dictionary).data_type(addr))
            .or_else(|| crate::od::standard::data_type(addr))
            .ok_or_else(|| self.err(node, Some(addr), CanErrorKind::UnknownType))
    }

    /// Upload `addr` and decode it as `data_type` (or the type in the node's profile).
    pub fn upload_value(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        data_type: Option<DataType>,
    ) -> Result<Value, CanError> {
        let dt = self.data_type(node, addr, data_type)?;
        let raw = self.sdo_upload(node, addr)?;
        Value::decode(dt, &raw).map_err(|e| self.err(node, Some(addr), CanErrorKind::Value(e)))
    }

    /// Encode `value` as `data_type` (or the profile's type) and download it to `addr`.
    pub fn download_value(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        value: &Value,
        data_type: Option<DataType>,
    ) -> Result<(), CanError> {
        let dt = self.data_type(node, addr, data_type)?;
        let bytes = value
            .encode(dt)
            .map_err(|e| self.err(node, Some(addr), CanErrorKind::Value(e)))?;
        self.sdo_download(node, addr, &bytes)
    }

    pub(super) fn upload_u32(&mut self, node: u8, addr: ObjectAddress) -> Result<u32, CanError> {
        let raw = self.sdo_upload(node, addr)?;
        let mut b = [0u8; 4];
        let n = raw.len().min(4);
        if let (Some(d), Some(s)) = (b.get_mut(..n), raw.get(..n)) {
            d.copy_from_slice(s);
        }
        Ok(u32::from_le_bytes(b))
    }

    pub(super) fn write_uint(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        v: u64,
        dt: DataType,
    ) -> Result<(), CanError> {
        self.download_value(node, addr, &Value::Uint(v), Some(dt))
    }
}
