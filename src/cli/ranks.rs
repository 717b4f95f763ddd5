//! Commands on several MPI ranks (`mpirun -np N hgym-mpi train|eval|run|validate ...`): every
//! rank runs the whole command and takes the same decisions (see `hgym::flow::ranks`); rank 0
//! writes the results where the command line says, every other rank into a scratch folder of
//! its own, deleted when the command ends, so that the code writing files needs no rank checks.
//! A run to resume is copied into the scratch folder first: every rank then continues from rank
//! 0's checkpoint (each rank checkpoints on its own clock, so their own copies could differ).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// A rank's scratch folder, removed on drop.
pub struct Scratch(PathBuf);

impl Scratch {
    /// `<temp>/hgym-rank<r>-<pid>`, empty.
    fn new(rank: usize) -> Result<Self> {
        let dir = std::env::temp_dir().join(format!("hgym-rank{rank}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create the scratch folder {}", dir.display()))?;
        Ok(Self(dir))
    }

    /// Where this rank writes what rank 0 writes to `out`.
    pub fn output(&self, out: &Path) -> PathBuf {
        self.0.join("out").join(out.file_name().unwrap_or(out.as_os_str()))
    }

    /// A copy of the run folder `dir` (to resume) inside the scratch folder.
    pub fn copy_of(&self, dir: &Path) -> Result<PathBuf> {
        let to = self.0.join("resume").join(dir.file_name().unwrap_or(dir.as_os_str()));
        copy_dir(dir, &to).with_context(|| format!("copying the run folder {} to resume it on this rank", dir.display()))?;
        Ok(to)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Points the outputs of `command` into a scratch folder on every rank but 0, then waits until
/// every rank is there (so that rank 0 changes nothing another rank is still copying). `None`
/// on one process and on rank 0.
pub fn scatter_outputs(command: &mut crate::Command) -> Result<Option<Scratch>> {
    let (rank, size) = hgym::flow::ranks::rank();
    if size == 1 {
        return Ok(None);
    }
    let scratch = if rank == 0 {
        None
    } else {
        let s = Scratch::new(rank)?;
        match command {
            crate::Command::Train(a) => a.write_into(&s)?,
            crate::Command::Eval(a) => a.write_into(&s),
            crate::Command::Run(a) => a.write_into(&s),
            // Validation writes from rank 0 only (`hgym::validate`); the others are refused.
            _ => {}
        }
        Some(s)
    };
    hgym::flow::ranks::barrier();
    Ok(scratch)
}

/// Copies the folder `from` (files and subfolders) to `to`.
fn copy_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let target = to.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            std::fs::copy(entry.path(), &target)?;
        }
    }
    Ok(())
}

/// How a failing rank ends an MPI job. Ranks that did not fail would wait in the solver's next
/// exchange for the one that did, so the job is aborted; but an abort kills every rank at once,
/// also one still on its way to removing its scratch folder. Bad input fails on every rank
/// alike, so a failing rank first waits (at most [`Ending::GRACE`]) in a barrier of its own
/// communicator, which only failing ranks enter: when all ranks fail, all have cleaned up before
/// the abort; when some do not, the wait runs out and they are aborted as before.
#[cfg(feature = "mpi")]
pub struct Ending(mpi::topology::SimpleCommunicator);

/// One process: nothing to end but itself.
#[cfg(not(feature = "mpi"))]
pub struct Ending;

#[cfg(feature = "mpi")]
impl Ending {
    /// How long a failing rank waits for the others to fail too.
    const GRACE: std::time::Duration = std::time::Duration::from_secs(5);

    /// A collective: every rank calls it once, at start-up.
    pub fn new(world: &mpi::topology::SimpleCommunicator) -> Self {
        use mpi::traits::Communicator;
        Self(world.duplicate())
    }

    /// Aborts the job with `code` once every rank failed or the grace time ran out (nothing on
    /// one process).
    pub fn abort(self, code: i32) {
        use mpi::traits::{Communicator, CommunicatorCollectives};
        if self.0.size() == 1 {
            return;
        }
        let start = std::time::Instant::now();
        let mut request = self.0.immediate_barrier();
        while start.elapsed() < Self::GRACE {
            match request.test() {
                Ok(_) => break,
                Err(pending) => request = pending,
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        self.0.abort(code)
    }
}

#[cfg(not(feature = "mpi"))]
impl Ending {
    /// Nothing to abort.
    pub fn abort(self, _code: i32) {}
}
