//! The session thread's mailbox work while the cycle runs: polling the drives' mailboxes for
//! emergencies, and the application's SDO requests ([`Master::sdo_upload`],
//! [`Master::sdo_download`]). Its frames ride along in the cycle thread's exchanges; nothing
//! here runs on the cycle thread.
//!
//! [`Master::sdo_upload`]: crate::Master::sdo_upload
//! [`Master::sdo_download`]: crate::Master::sdo_download

use super::coe::{CoeClient, CoeError, EmergencyLog, MailboxSms};
use super::error::{DriveRef, ErrorKind, MasterError};
use super::exec;
use crate::od::ObjectAddress;
use std::collections::HashMap;
use std::future::Future;
use std::pin::Pin;
use std::sync::mpsc;
use std::time::Duration;

/// How long one supervisory mailbox poll during the cycle may take.
const POLL_TIMEOUT: Duration = Duration::from_millis(250);

/// How many drives one emergency poll reads at once: each has one frame in flight, and the
/// cycle's own frames need the rest of ethercrab's storage ([`crate::bus::MAX_FRAMES`]).
const POLLED_AT_ONCE: usize = 4;

/// One drive's poll: its station address, mailbox counter and SyncManagers when it answered.
type Polled<'f> = Pin<Box<dyn Future<Output = Option<(u16, u8, MailboxSms)>> + 'f>>;

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
/// mailbox counter (a device drops a request whose counter repeats the last one's) and its
/// mailbox SyncManagers, read once (by station address).
pub(crate) struct Mailboxes {
    devices: Vec<MailboxDevice>,
    counters: HashMap<u16, u8>,
    sms: HashMap<u16, MailboxSms>,
    log: EmergencyLog,
    timeout: Duration,
}

impl Mailboxes {
    pub fn new(devices: Vec<MailboxDevice>, log: EmergencyLog, timeout: Duration) -> Self {
        Self {
            devices,
            counters: HashMap::new(),
            sms: HashMap::new(),
            log,
            timeout,
        }
    }

    /// Read each drive's mailbox once (emergencies land in the log), giving up as soon as
    /// `finished` says the cycle has ended (no frame carries a request then, and a lost segment
    /// must not hold the session up). [`POLLED_AT_ONCE`] drives are read at once, their frames
    /// in the same cycles, and the mailbox SyncManagers only at the first poll: the session
    /// thread wakes for a poll's frames once per cycle, not once per drive and frame (issue 40).
    pub fn poll(&mut self, md: &ethercrab::MainDevice<'_>, finished: &dyn Fn() -> bool) {
        // A poll only reads what is waiting: a few cycles.
        let t = self.timeout.min(POLL_TIMEOUT);
        let polled: Vec<(u16, DriveRef, bool)> = self
            .devices
            .iter()
            .filter(|d| d.polled)
            .map(|d| (d.address, d.drive.clone(), d.complete_access))
            .collect();
        for group in polled.chunks(POLLED_AT_ONCE) {
            if finished() {
                break;
            }
            let log = &self.log;
            let futs: Vec<Polled<'_>> = group
                .iter()
                .map(|(address, drive, ca)| {
                    let (address, drive, ca) = (*address, drive.clone(), *ca);
                    let last = self.counters.get(&address).copied().unwrap_or(0);
                    let sms = self.sms.get(&address).copied();
                    Box::pin(async move {
                        let c = match sms {
                            Some(s) => CoeClient::with_sms(md, address, drive, log.clone(), s),
                            None => CoeClient::new(md, address, drive, log.clone()).await.ok()?,
                        };
                        let mut c = c
                            .with_complete_access(ca)
                            .with_timeout(t)
                            .with_counter(last);
                        let _ = c.drain().await;
                        Some((address, c.counter(), c.sms()))
                    }) as Polled<'_>
                })
                .collect();
            let done = exec::run_remote_unless(
                &|| "polling the drives' mailboxes".into(),
                t,
                exec::join_all(futs),
                finished,
            );
            for (address, counter, sms) in done.into_iter().flatten().flatten() {
                self.counters.insert(address, counter);
                self.sms.insert(address, sms);
            }
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
        let sms = self.sms.get(&d.address).copied();
        let (address, drive, ca, log) = (d.address, d.drive.clone(), d.complete_access, &self.log);
        let what_drive = drive.clone();
        let r = exec::run_remote_unless(
            &|| format!("{what_drive}: mailbox exchange"),
            timeout,
            async {
                let c = match sms {
                    Some(s) => CoeClient::with_sms(md, address, drive, log.clone(), s),
                    None => CoeClient::new(md, address, drive, log.clone()).await?,
                };
                let mut c = c
                    .with_complete_access(ca)
                    .with_timeout(timeout)
                    .with_counter(last);
                let r = op(&mut c).await;
                Ok::<_, CoeError>((r, c.counter(), c.sms()))
            },
            finished,
        );
        match r {
            Ok(Ok((r, counter, sms))) => {
                self.counters.insert(address, counter);
                self.sms.insert(address, sms);
                r.map_err(|e| super::bus::SessionError::Coe(e).into())
            }
            Ok(Err(e)) => Err(super::bus::SessionError::Coe(e).into()),
            Err(e) => Err(exec::exec_error(self.devices.get(i).map(|d| &d.drive), e)),
        }
    }
}
