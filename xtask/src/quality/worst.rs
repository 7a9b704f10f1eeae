//! `--worst R` / `--worst-cli R` / `--worst-bounded R`: each of lodgen's
//! levels through `lodgen_pm::polish::fix_worst` (up to R rounds) before the
//! table measures it, judged by the table's measurement (`--worst`), by the
//! command's default one (`--worst-cli`, `MeasureOptions::DEFAULT`: what
//! `lodgen --fix-worst` runs) or by the bounded maximum (`--worst-bounded`,
//! `MeasureOptions::BOUNDED`: `lodgen --measure bounded --fix-worst`).

use anyhow::Result;
use lodgen_pm::metric::{MeasureOptions, MeshRef, Reference};
use lodgen_pm::polish::{fix_worst, WorstOptions};
use lodgen_pm::Mesh;

/// Which measurement finds each round's maximum and judges its move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Judge {
    Table,
    Command,
    Bounded,
}

/// Fixes the worst spot of each of `levels` (of `m`), printing what each
/// round did to stderr.
pub fn fix_levels(
    reference: &Reference,
    m: &Mesh,
    levels: &mut [Mesh],
    name: &str,
    mopts: &MeasureOptions,
    (rounds, judge): (u32, Judge),
) -> Result<()> {
    if rounds == 0 {
        return Ok(());
    }
    let wopts = WorstOptions {
        rounds,
        ..WorstOptions::DEFAULT
    };
    let judge = match judge {
        Judge::Table => *mopts,
        Judge::Command => MeasureOptions::DEFAULT,
        Judge::Bounded => MeasureOptions::BOUNDED,
    };
    for level in levels {
        let original = MeshRef::new(&m.positions, &m.triangles);
        let fix = fix_worst(reference, original, level, &judge, &wopts)?;
        eprintln!(
            "quality: {name} {} triangles, worst spot fixed in {} rounds: H {:.4} -> {:.4} %, \
             RMS {:.5} -> {:.5} %",
            level.triangles.len(),
            fix.kept,
            fix.before.hausdorff_percent(),
            fix.error.hausdorff_percent(),
            fix.before.rms_percent(),
            fix.error.rms_percent()
        );
    }
    Ok(())
}
