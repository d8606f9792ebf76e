//! Error control: heartbeat consumer and node guarding.

use super::*;

impl<T: CanTransport> Master<T> {
    /// Set up error control of `node` (writes 1017h or 100Ch/100Dh) and start watching it.
    pub fn supervise(&mut self, node: u8, s: Supervision) -> Result<(), CanError> {
        self.check_node(node)?;
        let has = |m: &Self, i: u16| {
            m.profile(node)
                .is_none_or(|p| Dictionary::new(p.dictionary).object(i).is_some())
        };
        let now = self.t.now_us();
        match s {
            Supervision::Heartbeat {
                producer_ms,
                consumer_ms,
            } => {
                if u64::from(consumer_ms) <= u64::from(producer_ms) {
                    return Err(self.err(
                        node,
                        None,
                        CanErrorKind::Invalid(format!(
                            "heartbeat consumer time {consumer_ms} ms must exceed the producer \
                             time {producer_ms} ms"
                        )),
                    ));
                }
                if !has(self, 0x1017) {
                    return Err(self.err(
                        node,
                        Some(ObjectAddress::new(0x1017, 0)),
                        CanErrorKind::Invalid(
                            "the drive produces no heartbeat (no 1017h): supervise it by node \
                             guarding"
                                .into(),
                        ),
                    ));
                }
                if has(self, 0x100C) {
                    self.write_uint(node, ObjectAddress::new(0x100C, 0), 0, DataType::Unsigned16)?;
                }
                self.write_uint(
                    node,
                    ObjectAddress::new(0x1017, 0),
                    u64::from(producer_ms),
                    DataType::Unsigned16,
                )?;
                if let Some(sl) = self.slot_mut(node) {
                    sl.guard = None;
                    sl.hb_timeout_us = Some(u64::from(consumer_ms) * 1000);
                    sl.hb_lost = false;
                    sl.last_seen_us = Some(now);
                }
            }
            Supervision::Guarding {
                guard_ms,
                life_factor,
            } => {
                if self.profile(node).is_some_and(|p| !p.comm.guarding) {
                    return Err(self.err(
                        node,
                        None,
                        CanErrorKind::Invalid("the drive has no node guarding".into()),
                    ));
                }
                if guard_ms == 0 || life_factor == 0 {
                    return Err(self.err(
                        node,
                        None,
                        CanErrorKind::Invalid("guard time and life-time factor must be > 0".into()),
                    ));
                }
                if has(self, 0x1017) {
                    self.write_uint(node, ObjectAddress::new(0x1017, 0), 0, DataType::Unsigned16)?;
                }
                self.write_uint(
                    node,
                    ObjectAddress::new(0x100C, 0),
                    u64::from(guard_ms),
                    DataType::Unsigned16,
                )?;
                self.write_uint(
                    node,
                    ObjectAddress::new(0x100D, 0),
                    u64::from(life_factor),
                    DataType::Unsigned8,
                )?;
                if let Some(sl) = self.slot_mut(node) {
                    sl.hb_timeout_us = None;
                    sl.guard = Some(Guard {
                        period_us: u64::from(guard_ms) * 1000,
                        life_factor: u32::from(life_factor),
                        next_us: now,
                        outstanding: 0,
                        toggle: None,
                        lost: false,
                    });
                }
            }
            Supervision::None => {
                if has(self, 0x1017) {
                    self.write_uint(node, ObjectAddress::new(0x1017, 0), 0, DataType::Unsigned16)?;
                }
                if has(self, 0x100C) {
                    self.write_uint(node, ObjectAddress::new(0x100C, 0), 0, DataType::Unsigned16)?;
                }
                if let Some(sl) = self.slot_mut(node) {
                    sl.hb_timeout_us = None;
                    sl.guard = None;
                }
            }
        }
        Ok(())
    }
}
