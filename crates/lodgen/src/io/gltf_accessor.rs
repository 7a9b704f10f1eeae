//! The glTF reader's accessors: every offset, length, stride and count
//! checked against its buffer view and the memory cap before anything is
//! allocated, sparse values applied, normalized integers mapped.

use gltf::json::accessor::{GenericComponentType, IndexComponentType, Type};
use gltf::json::validation::Checked;
use gltf::json::Root;

use super::error::{ErrorKind, Location, ReadError};
use super::gltf_data::{component_size, read_element};
use super::gltf_in::Reader;

impl Reader<'_> {
    pub(super) fn same_count<T>(
        &self,
        v: Vec<T>,
        n: usize,
        at: &str,
        name: &str,
    ) -> Result<Vec<T>, ReadError> {
        if v.len() != n {
            return Err(self.json_err(
                &format!("{at}.attributes.{name}"),
                format!("{name} has {} entries, POSITION has {n}", v.len()),
            ));
        }
        Ok(v)
    }

    /// Reads accessor `index` as `N`-component float vectors.
    pub(super) fn vectors<const N: usize>(
        &self,
        root: &Root,
        buffers: &[Vec<u8>],
        index: usize,
        at: &str,
    ) -> Result<Vec<[f32; N]>, ReadError> {
        let (values, dims) = self.accessor(root, buffers, index, at)?;
        if dims != N {
            return Err(self.json_err(
                at,
                format!("accessor {index} has {dims} components, expected {N}"),
            ));
        }
        let out: Vec<[f32; N]> = values
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|k| c[k] as f32))
            .collect();
        if let Some(i) = out.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            let value = out[i]
                .into_iter()
                .find(|x| !x.is_finite())
                .unwrap_or(f32::NAN);
            let name = at.rsplit('.').next().unwrap_or(at);
            return Err(self.err(
                Location::Json(format!("{at}[{i}]")),
                ErrorKind::NonFinite {
                    what: format!("{name} of vertex {i} (accessor {index})"),
                    value,
                },
            ));
        }
        Ok(out)
    }

    /// Reads every component of accessor `index` (sparse applied,
    /// normalized integers mapped to [-1, 1] / [0, 1]); returns the flat
    /// values and the number of components per element.
    pub(super) fn accessor(
        &self,
        root: &Root,
        buffers: &[Vec<u8>],
        index: usize,
        at: &str,
    ) -> Result<(Vec<f64>, usize), ReadError> {
        let here = format!("{at} (accessors[{index}])");
        let bad = |message: String| self.json_err(&here, message);
        let acc = root
            .accessors
            .get(index)
            .ok_or_else(|| bad("accessor does not exist".to_owned()))?;
        let Checked::Valid(GenericComponentType(ct)) = acc.component_type else {
            return Err(bad("invalid componentType".to_owned()));
        };
        let dims = match acc.type_ {
            Checked::Valid(Type::Scalar) => 1,
            Checked::Valid(Type::Vec2) => 2,
            Checked::Valid(Type::Vec3) => 3,
            Checked::Valid(Type::Vec4) => 4,
            _ => return Err(bad("accessor type is not SCALAR or VEC2..4".to_owned())),
        };
        let count = usize::try_from(acc.count.0).unwrap_or(usize::MAX);
        let elem = component_size(ct) * dims;
        // Check the data is there before allocating for it.
        let data = match acc.buffer_view {
            Some(view) => {
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                Some(self.view(root, buffers, view.value(), offset, count, elem, &here)?)
            }
            None => None,
        };
        // f64 values, then the caller's f32 copy: 12 bytes per component
        let bytes = (count as u64).saturating_mul(dims as u64 * 12);
        if bytes > self.budget.get() {
            return Err(bad(format!(
                "{count} elements would pass the reader's memory cap ({} bytes per byte of \
                 input, {} bytes left)",
                super::common::DECODED_BYTES_PER_INPUT_BYTE,
                self.budget.get()
            )));
        }
        self.budget.set(self.budget.get() - bytes);
        let mut values = vec![0.0f64; count * dims];
        if let Some((data, stride)) = data {
            for i in 0..count {
                read_element(
                    &data[i * stride..],
                    ct,
                    dims,
                    acc.normalized,
                    &mut values[i * dims..(i + 1) * dims],
                );
            }
        }
        if let Some(sparse) = &acc.sparse {
            let n = usize::try_from(sparse.count.0).unwrap_or(usize::MAX);
            let Checked::Valid(IndexComponentType(ict)) = sparse.indices.component_type else {
                return Err(bad("invalid sparse index componentType".to_owned()));
            };
            let isize_ = component_size(ict);
            let (idata, _) = self.view(
                root,
                buffers,
                sparse.indices.buffer_view.value(),
                sparse.indices.byte_offset.0,
                n,
                isize_,
                &here,
            )?;
            let (vdata, _) = self.view(
                root,
                buffers,
                sparse.values.buffer_view.value(),
                sparse.values.byte_offset.0,
                n,
                elem,
                &here,
            )?;
            let mut target = [0.0f64; 1];
            for k in 0..n {
                read_element(&idata[k * isize_..], ict, 1, false, &mut target);
                let i = target[0] as usize;
                if i >= count {
                    return Err(bad(format!(
                        "sparse index {i} is out of range ({count} elements)"
                    )));
                }
                read_element(
                    &vdata[k * elem..],
                    ct,
                    dims,
                    acc.normalized,
                    &mut values[i * dims..(i + 1) * dims],
                );
            }
        }
        Ok((values, dims))
    }

    /// The bytes of buffer view `view` starting at `offset`, checked to
    /// hold `count` elements of `elem` bytes; returns them and the stride.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn view<'b>(
        &self,
        root: &Root,
        buffers: &'b [Vec<u8>],
        view: usize,
        offset: u64,
        count: usize,
        elem: usize,
        here: &str,
    ) -> Result<(&'b [u8], usize), ReadError> {
        let bad = |message: String| self.json_err(here, message);
        let bv = root
            .buffer_views
            .get(view)
            .ok_or_else(|| bad(format!("bufferView {view} does not exist")))?;
        let buffer = buffers
            .get(bv.buffer.value())
            .ok_or_else(|| bad(format!("buffer {} does not exist", bv.buffer.value())))?;
        let stride = bv.byte_stride.map_or(elem, |s| s.0);
        if stride < elem {
            return Err(bad(format!(
                "byteStride {stride} is smaller than an element ({elem} bytes)"
            )));
        }
        let view_start = bv.byte_offset.map_or(0, |o| o.0);
        let view_end = view_start.checked_add(bv.byte_length.0);
        let needed = match count {
            0 => Some(0u64),
            c => (stride as u64)
                .checked_mul(c as u64 - 1)
                .and_then(|x| x.checked_add(elem as u64)),
        };
        let start = view_start.checked_add(offset);
        let end = start.zip(needed).and_then(|(s, n)| s.checked_add(n));
        match (start, end, view_end) {
            (Some(start), Some(end), Some(view_end)) if end <= view_end && view_end <= buffer.len() as u64 => {
                Ok((&buffer[start as usize..end as usize], stride))
            }
            _ => Err(self.err(
                Location::Json(here.to_owned()),
                ErrorKind::Truncated(format!(
                    "{count} elements of {elem} bytes do not fit in bufferView {view} (buffer {}, {} bytes)",
                    bv.buffer.value(),
                    buffer.len()
                )),
            )),
        }
    }
}
