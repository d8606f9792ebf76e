//! Drives: identity checks and configuration (PDO plan, sync, start-up values, axis).

use super::*;

impl<T: CanTransport> Master<T> {
    /// Check that `node` is the drive of `profile` (1000h, 1018h:01, 1018h:02).
    pub fn check_identity(
        &mut self,
        node: u8,
        profile: &'static CanDriveProfile,
    ) -> Result<(), CanError> {
        let device_type = self.upload_u32(node, ObjectAddress::new(0x1000, 0))?;
        let vendor = self.upload_u32(node, ObjectAddress::new(0x1018, 1))?;
        let product = self.upload_u32(node, ObjectAddress::new(0x1018, 2)).ok();
        if profile.identity.matches(device_type, vendor, product) {
            Ok(())
        } else {
            Err(self.err(
                node,
                None,
                CanErrorKind::Identity(format!(
                    "the node reports device type 0x{device_type:08X}, vendor 0x{vendor:08X}, \
                     product {}; the {} profile expects device type 0x{:08X}, vendor 0x{:08X}",
                    product.map_or("?".to_string(), |p| format!("0x{p:08X}")),
                    profile.name,
                    profile.identity.device_type,
                    profile.identity.vendor_id
                )),
            ))
        }
    }

    /// Configure `node` as a drive (in Pre-operational): identity check, supervision, enable
    /// preconditions ([`EnableConditions::settings`](crate::profile::EnableConditions)), the PDO
    /// plan, quick-stop option, initial mode, settings, cycle objects; then build its
    /// [`CanDrive`] with an [`Axis`]. Start it with [`Master::start`].
    pub fn configure_drive(&mut self, node: u8, setup: DriveSetup) -> Result<(), CanError> {
        self.check_node(node)?;
        let p = setup.profile;
        self.set_profile(node, p);
        self.check_identity(node, p)?;
        let caps = p.caps;
        let cycle = self.cfg.cycle_us;
        let min_pdo = u64::from(p.comm.rpdo_min_interval_us);
        if cycle < min_pdo {
            return Err(self.err(
                node,
                None,
                CanErrorKind::Invalid(format!(
                    "a {cycle} µs cycle sends each RPDO more often than the {} accepts (one \
                     frame per COB-ID per {min_pdo} µs)",
                    p.name
                )),
            ));
        }
        setup
            .plan
            .validate(p)
            .map_err(|e| self.err(node, None, CanErrorKind::Pdo(e)))?;
        self.nmt(node, NmtCommand::EnterPreOperational)?;
        self.supervise(node, setup.supervision)?;
        for s in p.enable.settings {
            let v = self.upload_u32(node, s.addr)?;
            if v & s.mask != s.value {
                if !s.writable {
                    return Err(self.err(
                        node,
                        Some(s.addr),
                        CanErrorKind::Precondition {
                            why: s.why,
                            addr_index: s.addr.index,
                            addr_sub: s.addr.sub,
                            value: u64::from(v),
                        },
                    ));
                }
                let nv = (v & !s.mask) | s.value;
                let dt = self.data_type(node, s.addr, None)?;
                let bytes = nv.to_le_bytes();
                let n = usize::from(dt.bit_len().unwrap_or(32) / 8).min(4);
                self.sdo_download(node, s.addr, bytes.get(..n).unwrap_or(&bytes))?;
            }
        }
        for w in setup.plan.writes(p, node) {
            self.sdo_download(node, w.addr, &w.bytes())?;
        }
        let dict = Dictionary::new(p.dictionary);
        if let Some(code) = setup.quick_stop_option
            && dict.object(0x605A).is_some()
        {
            self.download_value(
                node,
                ObjectAddress::new(0x605A, 0),
                &Value::Int(code.into()),
                None,
            )?;
        }
        self.download_value(
            node,
            ObjectAddress::new(0x6060, 0),
            &Value::Int(setup.initial_mode.as_i8().into()),
            None,
        )?;
        if self.cfg.sync_producer && p.comm.has_cycle_period {
            let g = u64::from(p.comm.cycle_period_granularity_us);
            if g == 0 || cycle % g == 0 {
                self.write_uint(
                    node,
                    ObjectAddress::new(0x1006, 0),
                    cycle,
                    DataType::Unsigned32,
                )?;
            }
        }
        // ip period in ms (ASDA-A2 60C2h:01, 1–20 ms), where the drive's range takes it (maxon
        // EPOS2's EDS file allows only 1 ms: a run that is not ip leaves it alone).
        let period_fits = dict.entry(ObjectAddress::new(0x60C2, 1)).is_some_and(|e| {
            let ms = i128::from(cycle / 1000);
            e.min.as_i128().is_none_or(|lo| ms >= lo) && e.max.as_i128().is_none_or(|hi| ms <= hi)
        });
        if period_fits && cycle % 1000 == 0 && (1000..=20_000).contains(&cycle) {
            self.write_uint(
                node,
                ObjectAddress::new(0x60C2, 1),
                cycle / 1000,
                DataType::Unsigned8,
            )?;
        }
        for (addr, v) in &setup.settings {
            self.download_value(node, *addr, v, None)?;
        }
        let axis_cfg = match setup.axis {
            Some(c) => c,
            None => {
                AxisConfig::for_cycle_time(&caps, Duration::from_micros(cycle), setup.initial_mode)
            }
        };
        let axis =
            Axis::new(caps, axis_cfg).map_err(|e| self.err(node, None, CanErrorKind::Axis(e)))?;
        let drive = CanDrive::new(node, p, setup.plan, axis)
            .map_err(|e| self.err(node, None, CanErrorKind::Field(e)))?;
        // Replace a previous configuration of this node.
        if let Some(old) = self.slot(node).and_then(|s| s.drive) {
            for r in self.tpdo_route.iter_mut() {
                if r.is_some_and(|(d, _)| usize::from(d) == old) {
                    *r = None;
                }
            }
            if let Some(slot) = self.drives.get_mut(old) {
                *slot = drive;
            }
        } else {
            self.drives.push(drive);
            let idx = self.drives.len() - 1;
            if let Some(s) = self.slot_mut(node) {
                s.drive = Some(idx);
            }
        }
        let idx = self.slot(node).and_then(|s| s.drive).unwrap_or(0);
        let routes: Vec<(u16, u8)> = self
            .drives
            .get(idx)
            .map(|d| {
                d.tpdos()
                    .iter()
                    .enumerate()
                    .map(|(i, s)| (s.cob, i as u8))
                    .collect()
            })
            .unwrap_or_default();
        for (c, i) in routes {
            if let Some(r) = self.tpdo_route.get_mut(usize::from(c)) {
                *r = Some((idx as u16, i));
            }
        }
        Ok(())
    }

    /// NMT start of `node`: PDOs run from now on.
    pub fn start(&mut self, node: u8) -> Result<(), CanError> {
        self.check_node(node)?;
        self.nmt(node, NmtCommand::Start)
    }
}
