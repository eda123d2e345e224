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
            let timeout = s.timeout.map(|t| sup.clock.to_tokio(t));
            let place = Place::spawn_with_mailbox(
                Place {
                    action: Arc::clone(&s.action),
                    timeout,
                    reports: sup.reports_tx.clone(),
                },
                mailbox::unbounded(),
            );
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

    /// Waits for a message or for action reports. Reports come on their own channel (no
    /// boxing, no actor message per report) and are drained in a batch: each is recorded in
    /// arrival order, then what is ready fires once.
    async fn next(
        &mut self,
        _: WeakActorRef<Self>,
        mailbox_rx: &mut MailboxReceiver<Self>,
    ) -> Result<Option<Signal<Self>>, Self::Error> {
        loop {
            if self.finished {
                return Ok(None);
            }
            let (Some(mut rx), Some(mut out)) = (self.reports_rx.take(), self.output_rx.take())
            else {
                return Ok(mailbox_rx.recv().await);
            };
            let got = tokio::select! {
                biased;
                sig = mailbox_rx.recv() => {
                    self.reports_rx = Some(rx);
                    self.output_rx = Some(out);
                    return Ok(sig);
                }
                Some(o) = out.recv() => {
                    self.action_output(o);
                    self.drain_output(&mut out);
                    self.reports_rx = Some(rx);
                    self.output_rx = Some(out);
                    continue;
                }
                r = rx.recv() => r,
            };
            let mut settle = false;
            if let Some(first) = got {
                self.drain_output(&mut out);
                settle |= self.action_done(first);
                for _ in 0..BATCH {
                    match rx.try_recv() {
                        Ok(d) => {
                            self.drain_output(&mut out);
                            settle |= self.action_done(d)
                        }
                        Err(_) => break,
                    }
                }
            }
            self.reports_rx = Some(rx);
            self.output_rx = Some(out);
            if settle {
                self.settle();
                self.schedule();
            }
        }
    }
}
