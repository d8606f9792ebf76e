//! NMT: state commands, boot-up waits, resets.

use super::*;

impl<T: CanTransport> Master<T> {
    /// Whether `node`'s power stage is enabled, from a fresh statusword (SDO) if the node
    /// serves SDO, else from the last TPDO. `None` if unknown.
    pub(super) fn power_stage(&mut self, node: u8) -> Option<State> {
        let serves = self
            .slot(node)
            .and_then(|s| s.nmt)
            .is_some_and(NmtState::serves_sdo);
        if serves
            && let Ok(raw) = self.sdo_upload(node, ObjectAddress::new(0x6041, 0))
            && let [a, b, ..] = raw[..]
        {
            return StatusWord::from_raw(u16::from_le_bytes([a, b])).state();
        }
        self.drive(node).and_then(|d| d.statusword().state())
    }

    /// Send an NMT command to `node` (0 = every node). Stop and the resets are refused to a node
    /// whose drive is energised (see the module documentation); for node 0 every known
    /// node is checked.
    pub fn nmt(&mut self, node: u8, cmd: NmtCommand) -> Result<(), CanError> {
        if node > 127 {
            return self.check_node(node);
        }
        if cmd.disturbs_enabled_drive() {
            let targets: Vec<u8> = if node == 0 {
                (1..=127u8)
                    .filter(|n| self.slot(*n).is_some_and(|s| s.seen))
                    .collect()
            } else {
                vec![node]
            };
            for n in targets {
                if let Some(state) = self.power_stage(n)
                    && state.is_energised()
                {
                    return Err(self.err(n, None, CanErrorKind::NmtRefused { cmd, state }));
                }
            }
        }
        self.send(&cmd.frame(node))?;
        let expected = match cmd {
            NmtCommand::Start => Some(NmtState::Operational),
            NmtCommand::Stop => Some(NmtState::Stopped),
            NmtCommand::EnterPreOperational => Some(NmtState::PreOperational),
            _ => None,
        };
        let ids: Vec<u8> = if node == 0 {
            (1..=127).collect()
        } else {
            vec![node]
        };
        for n in ids {
            if let Some(s) = self.slot_mut(n)
                && s.seen
                && let Some(e) = expected
            {
                // The node does not confirm NMT commands; assume the state until the next
                // heartbeat says otherwise.
                s.nmt = Some(e);
            }
        }
        Ok(())
    }

    /// Wait until `node` sends a boot-up message counted after `after` boot-ups.
    pub(super) fn wait_boot(&mut self, node: u8, after: u32) -> Result<(), CanError> {
        let deadline = self.t.now_us().saturating_add(self.cfg.boot_timeout_us);
        let ok = self.pump_until(deadline, |m| m.boot_ups(node) > after)?;
        if ok {
            Ok(())
        } else {
            Err(self.err(
                node,
                None,
                CanErrorKind::NoBootUp(self.cfg.boot_timeout_us / 1000),
            ))
        }
    }

    /// Reset communication of `node` (refused while its drive is energised) and wait for its
    /// boot-up message.
    pub fn reset_communication(&mut self, node: u8) -> Result<(), CanError> {
        self.check_node(node)?;
        let before = self.boot_ups(node);
        self.nmt(node, NmtCommand::ResetCommunication)?;
        self.wait_boot(node, before)
    }

    /// Reset `node` (application and communication; refused while its drive is energised) and
    /// wait for its boot-up message.
    pub fn reset_node(&mut self, node: u8) -> Result<(), CanError> {
        self.check_node(node)?;
        let before = self.boot_ups(node);
        self.nmt(node, NmtCommand::ResetNode)?;
        self.wait_boot(node, before)
    }
}
