//! The cycle's side of its own frames ([`frames`](super::frames)): whose frames carry the
//! image, learning ethercrab's, and what the replies tell the session of the mailboxes.

use super::Cycle;
use super::frames::OwnFrames;
use crate::io::FrameLink;

/// Whose frames carry the process image (see [`frames`](super::frames)).
pub(super) enum OwnPath {
    /// ethercrab's (`tx_rx_dc`), for the whole run.
    Off,
    /// ethercrab's, while the frames it sends are learnt; tries left.
    Learning { tries: u8 },
    /// ecdrive's own.
    On(OwnFrames),
}

/// How many cycles learning ethercrab's frames may take before the cycle stays on its path
/// (a mailbox frame of the session's between them spoils a try).
const LEARNING_TRIES: u8 = 5;

impl OwnPath {
    /// At the start of a run: learning ethercrab's frames, unless the settings ask for them
    /// throughout.
    pub(super) fn new(own_frames: bool) -> Self {
        if own_frames {
            OwnPath::Learning {
                tries: LEARNING_TRIES,
            }
        } else {
            OwnPath::Off
        }
    }
}

impl<L: FrameLink> Cycle<'_, '_, L> {
    /// The image's outputs into ethercrab's copy of the process image.
    pub(super) fn outputs_to_ethercrab(&self) {
        for p in 0..self.states.len() {
            if let Ok(sd) = self.group.subdevice(self.md, p) {
                let mut io = sd.io_raw_mut();
                let (src, dst) = (self.image.outputs(p), io.outputs());
                if src.len() == dst.len() {
                    dst.copy_from_slice(src);
                }
            }
        }
    }

    /// Frames of ecdrive's own are out.
    pub(super) fn own_in_flight(&self) -> bool {
        matches!(&self.own, OwnPath::On(f) if f.in_flight())
    }

    /// Tell the session thread what the last reply said of the mailboxes, if that changed.
    pub(super) fn tell_mail(&mut self, full: Option<bool>) {
        if full != self.mail_told {
            self.mail_told = full;
            self.mail.set(full);
        }
    }

    /// After an exchange through ethercrab while learning: take its frames over, if they are
    /// the cycle's and nothing else came between them (see [`frames`](super::frames)). The SYNC0 shift is
    /// what ethercrab's wait to the next instant says it is.
    pub(super) fn learn(&mut self, dc_time: u64, next_wait_ns: u64) {
        self.pump.capture(false);
        let OwnPath::Learning { tries } = self.own else {
            return;
        };
        let period = self.consts.cycle_ns;
        self.consts.sync0_shift_ns = next_wait_ns.saturating_sub(period - dc_time % period);
        let learnt = {
            let (sent, overflow) = self.pump.captured();
            if overflow {
                Err("more frames than a capture keeps")
            } else {
                OwnFrames::learn(
                    sent,
                    &self.image,
                    &self.addresses,
                    &self.fmmus,
                    self.settings.drift_compensation,
                )
            }
        };
        self.own = match learnt {
            Ok(f) => {
                self.pump.watch_queue();
                self.pump.own_frames(&f.shapes());
                if let Some(plan) = self.wkc_plan.as_mut() {
                    plan.remember(f.logical());
                }
                OwnPath::On(f)
            }
            Err(_) if tries > 1 => OwnPath::Learning { tries: tries - 1 },
            Err(why) => {
                self.not_learnt = Some(why);
                OwnPath::Off
            }
        };
    }
}
