//! The coarse stage: after the first stage's clusters, groups of `GROUP`
//! neighbouring clusters (consecutive runs of triangles again, so compact
//! patches) are simplified the same way, in parallel rounds, holding only
//! the groups' borders; the first stage's other held vertices are free
//! now. So the whole-mesh walk that follows starts from far fewer
//! triangles (it is the part of the run on one core: its planning is
//! shared, its contractions are not).

use super::{rounds, Local, Tris};
use crate::mesh::adjacency::Fans;
use crate::simplify::{Simplifier, Stage};
use rayon::prelude::*;

/// First-stage clusters per coarse cluster (262,144 triangles with the
/// default clusters). On the CLI's path (`lodgen bunny-1m.obj --levels
/// 50%,10%,2%`, five coarse clusters) 16 and `KEEP_COARSE` 0.04 left the
/// 2 % level's Hausdorff distance 0.1290 → 0.1240 % and RMS 0.009783 →
/// 0.009750 %; 8 gave 0.1289 / 0.009884 (RMS +1 %), and with 0.06
/// 0.1318 / 0.009757 (docs/performance.md).
const GROUP: usize = 16;

/// At least this many coarse clusters, else the stage is left out.
const MIN_COARSE: usize = 4;

/// The coarse rounds stop at this fraction of the input (the first
/// stage's at `KEEP`): runs to more than half of it (above 2 %) leave the
/// stage out, so the whole-mesh passes have room before the target.
const KEEP_COARSE: f64 = 0.04;

impl Simplifier {
    /// After the first stage (clusters of `size` triangles): the coarse
    /// clusters of `GROUP × size` triangles simplified in rounds to
    /// `KEEP_COARSE` of the input, written back and their logs merged after
    /// the first stage's, when the run goes far enough and there are at
    /// least `MIN_COARSE` of them. The coarse clusters copy their live
    /// vertices' state (the whole mesh's arrays stay: at 15 % of the input
    /// the copies are small) and are written back in place.
    pub(super) fn run_coarse(&mut self, size: usize, factor: f32) {
        let nt = self.tris.len();
        let size = size * GROUP;
        let stop = (KEEP_COARSE * nt as f64) as usize;
        if nt.div_ceil(size) < MIN_COARSE
            || self.target as f64 > KEEP_COARSE / 2.0 * nt as f64
            || self.live_tris <= stop
        {
            return;
        }
        self.set_stage(Stage::Clustering);
        let home = self.homes(size);
        // (rebuilt at the end, as the first stage's)
        self.vtris = Fans::default();
        let this = &*self;
        let mut locals: Vec<Local> = (0..nt.div_ceil(size) as u32)
            .into_par_iter()
            .map(|c| this.coarse_cluster(c, size, &home))
            .filter(|l| !l.s.tris.is_empty())
            .collect();
        drop(home);
        self.set_stage(Stage::Contracting);
        let meter = self.meter.as_deref();
        rounds(
            &mut locals,
            self.live_tris,
            self.target,
            stop,
            factor,
            meter,
        );
        // (the coarse rounds count after the first stage's)
        let passes = std::mem::take(&mut self.stats.passes);
        let done: Vec<_> = locals.into_iter().map(|l| self.write_back(l)).collect();
        self.stats.passes += passes;
        self.merge_logs(done);
        let alive = &self.tri_alive;
        self.vtris = Fans::new(self.pos.len(), &self.tris, |t| alive[t]);
    }

    /// Coarse cluster `c`: the live triangles of `c·size..`, its vertices'
    /// quadrics and positions copied from the whole mesh.
    fn coarse_cluster(&self, c: u32, size: usize, home: &[u32]) -> Local {
        let nt = self.tris.len();
        let ids: Vec<u32> = (c as usize * size..((c as usize + 1) * size).min(nt))
            .filter(|&t| self.tri_alive[t])
            .map(|t| t as u32)
            .collect();
        let own = ids.iter().map(|&t| self.tris[t as usize]).collect();
        let fetch = |g: usize| (self.quadric[g], self.pos[g]);
        self.numbered(c, Tris::List(ids), own, home, fetch)
    }
}
