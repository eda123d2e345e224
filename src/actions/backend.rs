//! [`ProgramActions`]: a plan's program actions (`action = { command = … }`,
//! `{ worker = … }`) as a [`Backend`]: it registers each under the name its place's role
//! carries, one [`Worker`] per distinct worker program, and lets the workers go when the run
//! is over.

use std::time::Duration;

use super::{CommandAction, CommandSpec, DEFAULT_KILL_GRACE, Worker, WorkerSpec};
use crate::plan::ProgramAction;
use crate::runtime::{Backend, BackendError, RuntimeBuilder};

/// The program actions of a plan ([`Plan::programs`](crate::plan::Plan::programs)).
///
/// ```no_run
/// # use gspn::{actions::ProgramActions, io::ReadOptions, plan::read_plan, runtime::Backends};
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() {
/// let mut plan = read_plan("plans/python-workers/plan.toml".as_ref(), &ReadOptions::default()).unwrap();
/// let mut backends = Backends::default();
/// backends.push(ProgramActions::new(std::mem::take(&mut plan.programs)));
/// let (summary, _) = backends.run(plan.runtime_builder()).await.unwrap();
/// # let _ = summary;
/// # }
/// ```
#[derive(Debug)]
pub struct ProgramActions {
    programs: Vec<ProgramAction>,
    workers: Vec<(WorkerSpec, Worker)>,
}

impl ProgramActions {
    /// The backend registering `programs`.
    pub fn new(programs: Vec<ProgramAction>) -> Self {
        ProgramActions {
            programs,
            workers: Vec::new(),
        }
    }

    /// Registers every program on `run`, starting one worker per distinct worker program
    /// (argv, directory, environment, grace). Call it inside the run's tokio runtime.
    pub fn register(&mut self, mut run: RuntimeBuilder) -> RuntimeBuilder {
        for p in &self.programs {
            let kill_grace = p
                .kill_grace
                .map_or(DEFAULT_KILL_GRACE, Duration::from_secs_f64);
            match &p.worker_action {
                None => {
                    let mut spec = CommandSpec::new(p.argv.clone());
                    spec.cwd = p.cwd.clone();
                    spec.env = p.env.clone();
                    spec.timeout = p.timeout.map(Duration::from_secs_f64);
                    spec.kill_grace = kill_grace;
                    run = run.action(&p.name, CommandAction::new(spec));
                }
                Some(action) => {
                    let spec = WorkerSpec {
                        argv: p.argv.clone(),
                        cwd: p.cwd.clone(),
                        env: p.env.clone(),
                        kill_grace,
                    };
                    let worker = match self.workers.iter().find(|(s, _)| *s == spec) {
                        Some((_, w)) => w.clone(),
                        None => {
                            let w = Worker::start(spec.clone());
                            self.workers.push((spec, w.clone()));
                            w
                        }
                    };
                    run = run.action(&p.name, worker.action(action.clone()));
                }
            }
        }
        run
    }
}

impl Backend for ProgramActions {
    fn name(&self) -> &'static str {
        "programs"
    }

    fn attach(&mut self, run: RuntimeBuilder) -> Result<RuntimeBuilder, BackendError> {
        Ok(self.register(run))
    }

    /// Lets go of the workers: the last handle closes a worker's stdin, then its group gets
    /// SIGTERM and SIGKILL after the grace period.
    fn stop(&mut self) {
        self.workers.clear();
    }
}
