//! The input's vertex attributes per flat vertex for the
//! `LODGEN_progressive` stream: one channel per glTF attribute set.

use crate::scene::{Primitive, SourceMesh};

/// Every vertex attribute of `mesh` per flat vertex (primitives in order,
/// each its vertices in order: the numbering of the wedge ids in the log),
/// for the `LODGEN_progressive` stream: one channel per glTF attribute
/// some primitive has, named by its semantic (`NORMAL`, `TANGENT`,
/// `TEXCOORD_n`, `COLOR_n`, `JOINTS_n` as exact small integers,
/// `WEIGHTS_n`), values exactly the input's; a primitive without an
/// attribute gets zeros there (white for colours). Each wedge's group is
/// its primitive.
pub fn stream_attributes(mesh: &SourceMesh) -> lodgen_pm::stream::WedgeAttributes {
    use lodgen_pm::stream::{Channel, WedgeAttributes};
    let prims = &mesh.primitives;
    let sets = |f: &dyn Fn(&Primitive) -> usize| prims.iter().map(f).max().unwrap_or(0);
    // set indices as named (a primitive may have COLOR_1 without COLOR_0);
    // absent ones are filtered out below
    let (uvs, colors, joints) = (
        1 + sets(&|p| p.extra_texcoords.len()),
        1 + sets(&|p| p.extra_colors.len()),
        1 + sets(&|p| p.extra_joints.len()),
    );
    let candidates = [Attr::Normal, Attr::Tangent]
        .into_iter()
        .chain((0..uvs).map(Attr::Uv))
        .chain((0..colors).map(Attr::Color))
        .chain((0..joints).flat_map(|i| [Attr::Joints(i), Attr::Weights(i)]));
    let present: Vec<Attr> = candidates
        .filter(|&a| {
            prims
                .iter()
                .any(|p| a.fetch(p, 0, &mut Vec::new()).is_some())
        })
        .collect();
    let count: usize = prims.iter().map(|p| p.positions.len()).sum();
    let stride: usize = present.iter().map(|a| a.components()).sum();
    let mut values = Vec::with_capacity(count * stride);
    let mut groups = Vec::with_capacity(count);
    for (pi, p) in prims.iter().enumerate() {
        for v in 0..p.positions.len() {
            for a in &present {
                if a.fetch(p, v, &mut values).is_none() {
                    // white for a missing colour, zeros otherwise
                    let missing = if matches!(a, Attr::Color(_)) {
                        1.0
                    } else {
                        0.0
                    };
                    values.extend(std::iter::repeat_n(missing, a.components()));
                }
            }
            groups.push(pi as u32);
        }
    }
    WedgeAttributes {
        channels: present
            .iter()
            .map(|a| Channel {
                name: a.name(),
                components: a.components() as u8,
            })
            .collect(),
        values,
        groups,
        count,
    }
}

/// One glTF vertex attribute set of a [`Primitive`].
#[derive(Clone, Copy, Debug)]
enum Attr {
    Normal,
    Tangent,
    Uv(usize),
    Color(usize),
    Joints(usize),
    Weights(usize),
}

impl Attr {
    fn name(self) -> String {
        match self {
            Attr::Normal => "NORMAL".into(),
            Attr::Tangent => "TANGENT".into(),
            Attr::Uv(i) => format!("TEXCOORD_{i}"),
            Attr::Color(i) => format!("COLOR_{i}"),
            Attr::Joints(i) => format!("JOINTS_{i}"),
            Attr::Weights(i) => format!("WEIGHTS_{i}"),
        }
    }

    fn components(self) -> usize {
        match self {
            Attr::Normal => 3,
            Attr::Uv(_) => 2,
            _ => 4,
        }
    }

    /// Append vertex `v`'s values as `f32` (joints exactly); `None` when
    /// `p` lacks the set (or the vertex).
    fn fetch(self, p: &Primitive, v: usize, out: &mut Vec<f32>) -> Option<()> {
        fn put<const N: usize, T: Copy + Into<f64>>(
            set: Option<&Vec<[T; N]>>,
            v: usize,
            out: &mut Vec<f32>,
        ) -> Option<()> {
            out.extend(set?.get(v)?.iter().map(|&c| c.into() as f32));
            Some(())
        }
        fn nth<'a, X>(
            first: &'a Option<Vec<X>>,
            extra: &'a [Vec<X>],
            i: usize,
        ) -> Option<&'a Vec<X>> {
            if i == 0 {
                first.as_ref()
            } else {
                extra.get(i - 1)
            }
        }
        match self {
            Attr::Normal => put(p.normals.as_ref(), v, out),
            Attr::Tangent => put(p.tangents.as_ref(), v, out),
            Attr::Uv(i) => put(nth(&p.texcoords, &p.extra_texcoords, i), v, out),
            Attr::Color(i) => put(nth(&p.colors, &p.extra_colors, i), v, out),
            Attr::Joints(i) => put(nth(&p.joints, &p.extra_joints, i), v, out),
            Attr::Weights(i) => put(nth(&p.weights, &p.extra_weights, i), v, out),
        }
    }
}
