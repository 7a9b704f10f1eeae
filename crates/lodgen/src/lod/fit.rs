//! The per-level attribute fit: which channels are fitted ([`Channels`]),
//! the input surface they are fitted to ([`FitSource`]), and writing fitted
//! values back as valid attributes.

use lodgen_pm::attrfit::Channel;
use lodgen_pm::{Mesh, Simplified};

use crate::scene::{Primitive, SourceMesh};

use super::flat::Flat;
use super::unit::{normalize3, orthogonal_tangent};
use super::wedges::wedge_of_vertex;

/// Which attributes are fitted per level (`lodgen_pm::attrfit`), and where
/// each sits in a wedge's value vector; present when some primitive has it.
#[derive(Clone, Debug, Default)]
pub(super) struct Channels {
    normal: Option<usize>,
    uv: Option<usize>,
    /// Tangent xyz (w, the handedness, is the source's).
    tangent: Option<usize>,
    extra_uv: Vec<usize>,
    color: Option<usize>,
    /// `COLOR_1`, `COLOR_2`, …
    extra_color: Vec<usize>,
    dims: usize,
}

impl Channels {
    fn of(mesh: &SourceMesh) -> Channels {
        let any = |f: &dyn Fn(&Primitive) -> bool| mesh.primitives.iter().any(f);
        let mut c = Channels::default();
        let mut take = |present: bool, n: usize| {
            present.then(|| {
                c.dims += n;
                c.dims - n
            })
        };
        let normal = take(any(&|p| p.normals.is_some()), 3);
        let uv = take(any(&|p| p.texcoords.is_some()), 2);
        let tangent = take(any(&|p| p.tangents.is_some()), 3);
        let extra = mesh
            .primitives
            .iter()
            .map(|p| p.extra_texcoords.len())
            .max()
            .unwrap_or(0);
        let extra_uv: Vec<usize> = (0..extra).filter_map(|_| take(true, 2)).collect();
        let color = take(any(&|p| p.colors.is_some()), 4);
        let extra = mesh
            .primitives
            .iter()
            .map(|p| p.extra_colors.len())
            .max()
            .unwrap_or(0);
        let extra_color: Vec<usize> = (0..extra).filter_map(|_| take(true, 4)).collect();
        Channels {
            normal,
            uv,
            tangent,
            extra_uv,
            color,
            extra_color,
            dims: c.dims,
        }
    }

    /// The component range of every channel.
    fn ranges(&self) -> Vec<Channel> {
        let mut out = Vec::new();
        let mut put = |start: Option<usize>, n: usize, bounded: bool| {
            if let Some(i) = start {
                out.push(Channel {
                    components: i..i + n,
                    bounded,
                });
            }
        };
        // unit vectors are renormalised; UVs and colours never extrapolate
        put(self.normal, 3, false);
        put(self.uv, 2, true);
        put(self.tangent, 3, false);
        for &i in &self.extra_uv {
            put(Some(i), 2, true);
        }
        put(self.color, 4, true);
        for &i in &self.extra_color {
            put(Some(i), 4, true);
        }
        out
    }

    /// The channel values of vertex `v` of `p` (defaults where it lacks one).
    fn values(&self, p: &Primitive, v: usize, out: &mut Vec<f32>) {
        let start = out.len();
        out.resize(start + self.dims, 0.0);
        let o = &mut out[start..];
        if let Some(i) = self.normal {
            let n = p
                .normals
                .as_ref()
                .map_or([0.0, 0.0, 1.0], |a| normalize3(a[v]));
            o[i..i + 3].copy_from_slice(&n);
        }
        if let Some(i) = self.uv {
            o[i..i + 2].copy_from_slice(&p.texcoords.as_ref().map_or([0.0; 2], |a| a[v]));
        }
        if let Some(i) = self.tangent {
            let t = p.tangents.as_ref().map_or([1.0, 0.0, 0.0, 1.0], |a| a[v]);
            o[i..i + 3].copy_from_slice(&t[..3]);
        }
        for (k, &i) in self.extra_uv.iter().enumerate() {
            o[i..i + 2].copy_from_slice(&p.extra_texcoords.get(k).map_or([0.0; 2], |a| a[v]));
        }
        if let Some(i) = self.color {
            o[i..i + 4].copy_from_slice(&p.colors.as_ref().map_or([1.0; 4], |a| a[v]));
        }
        for (k, &i) in self.extra_color.iter().enumerate() {
            o[i..i + 4].copy_from_slice(&p.extra_colors.get(k).map_or([1.0; 4], |a| a[v]));
        }
        for x in o.iter_mut() {
            if !x.is_finite() {
                *x = 0.0;
            }
        }
    }

    /// Overwrite the last vertex pushed to `to` with fitted values `f`,
    /// made valid again: normals unit, tangents orthogonal to them, colours
    /// in [0, 1]. Only attributes the source primitive `from` has.
    pub(super) fn apply(&self, to: &mut Primitive, from: &Primitive, f: &[f32]) {
        if let (Some(i), Some(n), true) = (self.normal, to.normals.as_mut(), from.normals.is_some())
        {
            if let Some(last) = n.last_mut() {
                *last = normalize3([f[i], f[i + 1], f[i + 2]]);
            }
        }
        if let (Some(i), Some(uv), true) =
            (self.uv, to.texcoords.as_mut(), from.texcoords.is_some())
        {
            if let Some(last) = uv.last_mut() {
                *last = [f[i], f[i + 1]];
            }
        }
        let normal = to.normals.as_ref().and_then(|n| n.last().copied());
        if let (Some(i), Some(t), true) =
            (self.tangent, to.tangents.as_mut(), from.tangents.is_some())
        {
            if let Some(last) = t.last_mut() {
                *last = orthogonal_tangent([f[i], f[i + 1], f[i + 2], last[3]], normal);
            }
        }
        for (k, &i) in self.extra_uv.iter().enumerate() {
            if from.extra_texcoords.get(k).is_some() {
                if let Some(last) = to.extra_texcoords.get_mut(k).and_then(|a| a.last_mut()) {
                    *last = [f[i], f[i + 1]];
                }
            }
        }
        let rgba = |i: usize| [f[i], f[i + 1], f[i + 2], f[i + 3]].map(|x| x.clamp(0.0, 1.0));
        if let (Some(i), Some(c), true) = (self.color, to.colors.as_mut(), from.colors.is_some()) {
            if let Some(last) = c.last_mut() {
                *last = rgba(i);
            }
        }
        for (k, &i) in self.extra_color.iter().enumerate() {
            if from.extra_colors.get(k).is_some() {
                if let Some(last) = to.extra_colors.get_mut(k).and_then(|a| a.last_mut()) {
                    *last = rgba(i);
                }
            }
        }
    }
}

/// The input surface for the per-level attribute fit: flat positions,
/// triangles as wedge (representative flat vertex) triples, and every
/// flat vertex's channel values.
pub(super) struct FitSource {
    channels: Channels,
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    values: Vec<f32>,
}

impl FitSource {
    /// `None` when there is nothing to fit (no per-corner attributes
    /// besides joints and weights, which are never interpolated).
    pub(super) fn new(mesh: &SourceMesh, flat: &Flat, s: &Simplified) -> Option<FitSource> {
        let channels = Channels::of(mesh);
        if channels.dims == 0 || s.pm.wedges.is_none() {
            return None;
        }
        let mut values = Vec::with_capacity(channels.dims * flat.positions.len());
        for p in &mesh.primitives {
            for v in 0..p.positions.len() {
                channels.values(p, v, &mut values);
            }
        }
        let wedge = wedge_of_vertex(mesh, flat);
        let triangles = flat
            .indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| wedge[t[k] as usize]))
            .collect();
        Some(FitSource {
            channels,
            positions: flat.positions.to_vec(),
            triangles,
            values,
        })
    }

    pub(super) fn fit(&self, level: &Mesh, wedges: &[[u32; 3]]) -> Fitted {
        let values = lodgen_pm::attrfit::fit(
            lodgen_pm::attrfit::Source {
                positions: &self.positions,
                triangles: &self.triangles,
                values: &self.values,
                dims: self.channels.dims,
            },
            lodgen_pm::attrfit::Level {
                positions: &level.positions,
                triangles: &level.triangles,
                wedges,
            },
            &self.channels.ranges(),
        );
        Fitted {
            channels: self.channels.clone(),
            values,
        }
    }
}

/// A level's fitted values and the channel layout they use.
pub(super) struct Fitted {
    pub(super) channels: Channels,
    pub(super) values: lodgen_pm::attrfit::Fitted,
}
