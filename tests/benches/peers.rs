//! The peer benchmark: the workload of `../shared/PEERS.md` (icosphere 81,920 triangles,
//! soup 100,000, terrain 1,002,528, Sponza 66,454, the bunny 69,451 and `bunny-field`
//! flattened, 12.6 million; 1024 x 1024 primary rays in the renderer's tile order,
//! 1,048,576 incoherent rays and the shadow, ao and diffuse sets per mesh) traced by every exact raybench CPU backend and every
//! peer in one process: build times, Mrays/s of closest and any hits on 1 thread and on all
//! cores, ratios to Embree, node visits and primitive tests per ray, and the rays where each
//! differs from `bvh`. Prints tables and writes JSON ([`raybench_tests::peers`]).
//!
//! ```text
//! cargo bench -p raybench-tests --bench peers --features embree
//! cargo bench -p raybench-tests --bench peers -- --quick --meshes sphere --contestants bvh,packet,obvhs-bvh2
//! cargo bench -p raybench-tests --bench peers -- --diff before.json after.json
//! cargo bench -p raybench-tests --bench peers -- --diff b1.json,b2.json a1.json,a2.json
//! cargo bench -p raybench-tests --bench peers -- --help
//! ```

use raybench_tests::peers::{self, Command, USAGE};
use std::process::ExitCode;

fn main() -> ExitCode {
    let options = match peers::Options::parse(std::env::args().skip(1)) {
        Ok(Command::Run(o)) => o,
        Ok(Command::Help) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Ok(Command::List) => {
            for c in peers::contestants::all() {
                println!("{:<18} {:?}: {}", c.name, c.kind, c.description);
            }
            return ExitCode::SUCCESS;
        }
        Ok(Command::CacheProbe(per_size)) => {
            print!("{}", raybench_report::cache_probe::table(per_size));
            return ExitCode::SUCCESS;
        }
        Ok(Command::Diff(before, after, reference)) => {
            let pairs = before
                .iter()
                .zip(&after)
                .map(|(b, a)| {
                    let (before, after) = (peers::diff::read(b)?, peers::diff::read(a)?);
                    peers::diff::diff(&before, &after, reference.as_deref())
                        .map_err(|e| format!("{} over {}: {e}", a.display(), b.display()))
                })
                .collect::<Result<Vec<_>, _>>();
            let name = |p: &std::path::PathBuf| p.display().to_string();
            return match pairs {
                Ok(pairs) if pairs.len() == 1 => {
                    print!(
                        "{}",
                        peers::diff::markdown(&pairs[0], &name(&before[0]), &name(&after[0]))
                    );
                    ExitCode::SUCCESS
                }
                Ok(pairs) => {
                    let names: Vec<_> = before
                        .iter()
                        .zip(&after)
                        .map(|(b, a)| (name(b), name(a)))
                        .collect();
                    print!(
                        "{}",
                        peers::diff::markdown_across(&peers::diff::across(&pairs), &names)
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: peers --diff: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Err(e) => {
            eprintln!("error: peers: {e}");
            return ExitCode::from(2);
        }
    };
    // Each mesh's tables are printed, and the JSON rewritten, as soon as it is measured.
    let mut printed = false;
    let result = peers::run(&options, |report| {
        if !printed {
            print!("{}", report.header());
            printed = true;
        }
        let mesh = report.meshes.last().expect("a finished mesh");
        print!("{}", report.mesh_tables(mesh));
        peers::write_json(report, &options.json).map_err(|e| format!("cannot write the JSON: {e}"))
    });
    match result {
        Ok(report) => {
            print!("{}", report.skipped_meshes_text());
            print!("{}", report.cache_text());
            print!("{}", report.summary());
            if let Err(e) = peers::write_json(&report, &options.json) {
                eprintln!("error: peers: cannot write the JSON: {e}");
                return ExitCode::FAILURE;
            }
            println!("\nJSON: {}", options.json.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: peers: {e}");
            ExitCode::FAILURE
        }
    }
}
