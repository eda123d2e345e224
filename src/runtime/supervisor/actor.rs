//! The supervisor as a kameo actor: start-up (initial agents and actions), the message loop
//! (agent reports, action output, timers), and stop.

use super::*;

impl Actor for Supervisor {
    type Args = Supervisor;
    type Error = Infallible;

    async fn on_start(mut sup: Supervisor, me: ActorRef<Self>) -> Result<Self, Self::Error> {
        sup.me = Some(me.clone());
        sup.clock.restart();
        for s in &sup.setups {
            let place = s.instant.is_none().then(|| {
                Place::spawn_with_mailbox(
                    Place {
                        action: Arc::clone(&s.action),
                        reports: sup.reports_tx.clone(),
                    },
                    mailbox::unbounded(),
                )
            });
            sup.places.push(place);
        }
        let mut initial = Vec::new();
        for s in 0..sup.setups.len() {
            let p = sup.setups[s].place;
            for _ in 0..sup.eng.marking()[p] {
                let id = sup.eng.new_agent(p);
                initial.push((id, p));
            }
        }
        // The builder checked that there is one robot per initial agent.
        let robots = std::mem::take(&mut sup.robots);
        sup.eng
            .bind_robots(initial.iter().map(|&(id, _)| id), robots);
        let observed = sup.observed();
        sup.spawn_agent_actors(&initial);
        for &(id, p) in &initial {
            if observed {
                let robot = sup.eng.agent(id).and_then(|r| r.robot.clone());
                sup.emit(EventKind::AgentSpawned {
                    agent: id,
                    place: p,
                    robot,
                });
            }
        }
        for &(id, _) in &initial {
            sup.start_action(id, 0);
        }
        sup.progress.started.store(true, Ordering::Release);
        sup.settle();
        sup.schedule();
        if sup.finished {
            sup.kick();
        }
        Ok(sup)
    }

    async fn on_stop(
        &mut self,
        _: WeakActorRef<Self>,
        _: kameo::error::ActorStopReason,
    ) -> Result<(), Self::Error> {
        if !self.finished {
            self.stopping.get_or_insert(StopReason::Requested);
            self.finish();
        }
        self.clock.cancel();
        Ok(())
    }

    /// Waits for a message, action reports, output lines or (virtual time) sleep requests.
    /// Reports come on their own channel (no boxing, no actor message per report) and are
    /// drained in a batch. In real time each is recorded in arrival order, then what is ready
    /// fires once; in virtual time they wait in [`VirtualTime`] until no action is busy and
    /// are then applied in agent order ([`Supervisor::drive`]).
    async fn next(
        &mut self,
        _: WeakActorRef<Self>,
        mailbox_rx: &mut MailboxReceiver<Self>,
    ) -> Result<Option<Signal<Self>>, Self::Error> {
        loop {
            if self.finished {
                return Ok(None);
            }
            let (Some(mut rx), Some(mut out), Some(mut sleeps)) = (
                self.reports_rx.take(),
                self.output_rx.take(),
                self.sleeps_rx.take(),
            ) else {
                return Ok(mailbox_rx.recv().await);
            };
            let got = tokio::select! {
                biased;
                sig = mailbox_rx.recv() => {
                    self.reports_rx = Some(rx);
                    self.output_rx = Some(out);
                    self.sleeps_rx = Some(sleeps);
                    return Ok(sig);
                }
                Some(o) = out.recv() => {
                    self.line(o);
                    self.drain_output(&mut out);
                    self.reports_rx = Some(rx);
                    self.output_rx = Some(out);
                    self.sleeps_rx = Some(sleeps);
                    continue;
                }
                Some(req) = sleeps.recv() => {
                    // A sleep asked for while the run stops ends at once (its waker dropped).
                    let now = self.now();
                    if self.stopping.is_none() {
                        self.vt.sleep(now, req);
                    }
                    while let Ok(req) = sleeps.try_recv() {
                        if self.stopping.is_none() {
                            self.vt.sleep(now, req);
                        }
                    }
                    self.reports_rx = Some(rx);
                    self.output_rx = Some(out);
                    self.sleeps_rx = Some(sleeps);
                    self.drive();
                    continue;
                }
                r = rx.recv() => r,
            };
            let mut settle = false;
            if let Some(first) = got {
                self.drain_output(&mut out);
                settle |= self.report(first);
                for _ in 0..BATCH {
                    match rx.try_recv() {
                        Ok(d) => {
                            self.drain_output(&mut out);
                            settle |= self.report(d)
                        }
                        Err(_) => break,
                    }
                }
            }
            self.reports_rx = Some(rx);
            self.output_rx = Some(out);
            self.sleeps_rx = Some(sleeps);
            if settle {
                self.settle();
                self.schedule();
            }
        }
    }
}

impl Supervisor {
    /// A report: kept for [`Supervisor::drive`] in virtual time (true: drive now), else
    /// recorded at once (true: fire what is ready).
    fn report(&mut self, done: ActionDone) -> bool {
        if !self.clock.is_discrete() {
            return self.action_done(done);
        }
        self.vt.report(done);
        if self.stopping.is_some() && !self.vt.busy() {
            // The last cancelled action ended: their ends, in agent order, then the end.
            self.deliver();
        }
        self.stopping.is_none()
    }

    /// An output line: kept with the reports in virtual time, else recorded at once.
    pub(super) fn line(&mut self, o: OutputLine) {
        if self.clock.is_discrete() {
            self.vt.output(o);
        } else {
            self.action_output(o);
        }
    }
}
