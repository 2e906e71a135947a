//! Arguments of `akl report`: working with report files.

use std::path::PathBuf;

/// `akl report ...`
#[derive(Debug, clap::Subcommand)]
pub(crate) enum ReportCommand {
    /// Join the reports of a run's shards (`akl execute --shard I/N --report ...`) into the
    /// report the whole run writes.
    ///
    /// The merged report holds every trial exactly as its shard wrote it, in trial order, with
    /// the totals, the failures by root cause and the pass rate's interval computed from them
    /// as a single run computes its own; `merged` lists the parts. Parts are joined only when
    /// they are parts of one run: the same akl version, spec, task, robot (with its meshes),
    /// settings, perception noise, seed, randomization and number of trials (hashes in each
    /// report's `identity`), every shard once, none interrupted (finish one with `akl execute
    /// ... --resume PART`). `akl validate SPEC --task T --from-report MERGED` then judges the
    /// trials by the deployment gate.
    ///
    /// Exit codes: 0 merged (whatever the trials' outcomes); 2 the parts cannot be merged (the
    /// message names the part and what differs, is missing or is given twice) or cannot be
    /// read; 1 the output cannot be written.
    Merge(MergeArgs),
}

/// `akl report merge PARTS... -o FILE`
#[derive(Debug, clap::Args)]
pub(crate) struct MergeArgs {
    /// The shards' report files, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Where to write the merged report (atomically).
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: PathBuf,
    /// Also write the merged trials as JUnit XML to this file.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Print the merged report's summary as JSON (without the trials).
    #[arg(long)]
    pub json: bool,
}
