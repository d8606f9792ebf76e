//! The session thread's mailbox work while the cycle runs: polling the drives' mailboxes for
//! emergencies, and the application's SDO requests ([`Master::sdo_upload`],
//! [`Master::sdo_download`]). Its frames ride along in the cycle thread's exchanges; nothing
//! here runs on the cycle thread.
//!
//! [`Master::sdo_upload`]: crate::Master::sdo_upload
//! [`Master::sdo_download`]: crate::Master::sdo_download

use super::coe::{CoeClient, CoeError, EmergencyLog};
use super::error::{DriveRef, ErrorKind, MasterError};
use super::exec;
use crate::od::ObjectAddress;
use std::collections::HashMap;
use std::sync::mpsc;
use std::time::Duration;

/// How long one supervisory mailbox poll during the cycle may take.
const POLL_TIMEOUT: Duration = Duration::from_millis(250);

/// An SDO request of the application's, served by the session thread between its polls.
pub(crate) enum MailboxRequest {
    /// Read an entry (expedited, normal or segmented, as the device answers).
    Upload {
        position: u16,
        address: ObjectAddress,
        reply: mpsc::Sender<Result<Vec<u8>, MasterError>>,
    },
    /// Write an entry.
    Download {
        position: u16,
        address: ObjectAddress,
        data: Vec<u8>,
        reply: mpsc::Sender<Result<(), MasterError>>,
    },
}

/// One device the session may talk to over its mailbox.
pub(crate) struct MailboxDevice {
    pub position: u16,
    pub address: u16,
    pub drive: DriveRef,
    /// Polled for emergencies (the drives).
    pub polled: bool,
    pub complete_access: bool,
}

/// The session's mailbox state across the polls and requests of one run: every device's
/// mailbox counter (a device drops a request whose counter repeats the last one's).
pub(crate) struct Mailboxes {
    devices: Vec<MailboxDevice>,
    counters: HashMap<u16, u8>,
    log: EmergencyLog,
    timeout: Duration,
}

impl Mailboxes {
    pub fn new(devices: Vec<MailboxDevice>, log: EmergencyLog, timeout: Duration) -> Self {
        Self {
            devices,
            counters: HashMap::new(),
            log,
            timeout,
        }
    }

    /// Read each drive's mailbox once (emergencies land in the log), giving up as soon as
    /// `finished` says the cycle has ended (no frame carries a request then, and a lost segment
    /// must not hold the session up).
    pub fn poll(&mut self, md: &ethercrab::MainDevice<'_>, finished: &dyn Fn() -> bool) {
        for i in 0..self.devices.len() {
            if finished() {
                break;
            }
            if !self.devices.get(i).is_some_and(|d| d.polled) {
                continue;
            }
            // A poll only reads what is waiting: a few cycles.
            let t = self.timeout.min(POLL_TIMEOUT);
            let _ = self.exchange(md, i, t, finished, async |c| c.drain().await.map(|_| ()));
        }
    }

    /// Serve one request of the application's; the answer goes to its reply channel (a caller
    /// that gave up waiting is not an error).
    pub fn serve(
        &mut self,
        md: &ethercrab::MainDevice<'_>,
        request: MailboxRequest,
        finished: &dyn Fn() -> bool,
    ) {
        let t = self.timeout;
        match request {
            MailboxRequest::Upload {
                position,
                address,
                reply,
            } => {
                let r = self.at(position).and_then(|i| {
                    self.exchange(md, i, t, finished, async |c| c.upload(address, false).await)
                });
                let _ = reply.send(r);
            }
            MailboxRequest::Download {
                position,
                address,
                data,
                reply,
            } => {
                let r = self.at(position).and_then(|i| {
                    self.exchange(md, i, t, finished, async |c| {
                        c.download(address, &data, false).await
                    })
                });
                let _ = reply.send(r);
            }
        }
    }

    /// The index of the device at `position`, or why there is none to talk to.
    fn at(&self, position: u16) -> Result<usize, MasterError> {
        self.devices
            .iter()
            .position(|d| d.position == position)
            .ok_or_else(|| {
                let have: Vec<String> = self
                    .devices
                    .iter()
                    .map(|d| d.position.to_string())
                    .collect();
                MasterError::new(
                    None,
                    format!("selecting the device at position {position} for an SDO"),
                    ErrorKind::Config,
                    format!(
                        "no device with a CoE mailbox there (positions with one: {})",
                        if have.is_empty() {
                            "none".to_string()
                        } else {
                            have.join(", ")
                        }
                    ),
                )
            })
    }

    /// One mailbox exchange with device `i`, its counter carried on.
    fn exchange<T>(
        &mut self,
        md: &ethercrab::MainDevice<'_>,
        i: usize,
        timeout: Duration,
        finished: &dyn Fn() -> bool,
        op: impl AsyncFnOnce(&mut CoeClient<'_>) -> Result<T, CoeError>,
    ) -> Result<T, MasterError> {
        let Some(d) = self.devices.get(i) else {
            return Err(MasterError::new(
                None,
                "a mailbox exchange",
                ErrorKind::Config,
                "no such device",
            ));
        };
        let last = self.counters.get(&d.address).copied().unwrap_or(0);
        let (address, drive, ca, log) = (d.address, d.drive.clone(), d.complete_access, &self.log);
        let what_drive = drive.clone();
        let r = exec::run_remote_unless(
            &|| format!("{what_drive}: mailbox exchange"),
            timeout,
            async {
                let mut c = CoeClient::new(md, address, drive, log.clone())
                    .await?
                    .with_complete_access(ca)
                    .with_timeout(timeout)
                    .with_counter(last);
                let r = op(&mut c).await;
                Ok::<_, CoeError>((r, c.counter()))
            },
            finished,
        );
        match r {
            Ok(Ok((r, counter))) => {
                self.counters.insert(address, counter);
                r.map_err(|e| super::bus::SessionError::Coe(e).into())
            }
            Ok(Err(e)) => Err(super::bus::SessionError::Coe(e).into()),
            Err(e) => Err(exec::exec_error(self.devices.get(i).map(|d| &d.drive), e)),
        }
    }
}
