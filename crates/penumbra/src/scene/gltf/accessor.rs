//! Accessors: typed views of buffer bytes. Each is checked before anything is allocated:
//! its element count times its stride must fit its buffer view, the view its buffer, and the
//! values the memory budget; sparse substitutions are checked index by index.

use std::ops::Range;
use std::sync::Arc;

use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

use super::{GltfError, Reader, Result};

/// The most elements an accessor may have: a world holds at most 2^27 triangles, whose
/// 3·2^27 indices fit below 2^29.
const MAX_ELEMENTS: usize = 1 << 29;

/// How component bytes become a value of the output type.
pub(super) trait Component: Copy + Default {
    /// The value of one component of type `ty` in `bytes` (its size), normalized or not.
    fn decode(bytes: &[u8], ty: ComponentType, normalized: bool) -> Self;
}

impl Component for f32 {
    fn decode(b: &[u8], ty: ComponentType, normalized: bool) -> f32 {
        // The glTF spec's normalization: c / max, clamped at −1 for signed types.
        let (v, max) = match ty {
            ComponentType::I8 => (b[0] as i8 as f32, 127.0),
            ComponentType::U8 => (b[0] as f32, 255.0),
            ComponentType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0),
            ComponentType::U16 => (u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0),
            ComponentType::U32 => (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32, 1.0),
            ComponentType::F32 => (f32::from_le_bytes([b[0], b[1], b[2], b[3]]), 1.0),
        };
        match normalized {
            true => (v / max).max(-1.0),
            false => v,
        }
    }
}

impl Component for u32 {
    fn decode(b: &[u8], ty: ComponentType, _normalized: bool) -> u32 {
        match ty {
            ComponentType::U8 => b[0] as u32,
            ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
            ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            // Integer accessors are checked to be unsigned before decoding.
            _ => 0,
        }
    }
}

/// Bytes of one component.
fn size(ty: ComponentType) -> usize {
    match ty {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// Components of one element of a vector or scalar type (matrices are not read).
fn dims(ty: Type) -> Option<usize> {
    match ty {
        Type::Scalar => Some(1),
        Type::Vec2 => Some(2),
        Type::Vec3 => Some(3),
        Type::Vec4 => Some(4),
        Type::Mat2 | Type::Mat3 | Type::Mat4 => None,
    }
}

/// The bytes of a buffer view and the range an accessor reads of them.
struct Span {
    buffer: Arc<[u8]>,
    range: Range<usize>,
}

impl Reader<'_> {
    /// The values of accessor `index` (named at `at`), `dims_ok` components per element
    /// (the element count is the length over the components), each component decoded as
    /// `T`. `accept` says which component types the use allows.
    pub(super) fn read<T: Component>(
        &mut self,
        index: usize,
        at: &str,
        dims_ok: &[usize],
        accept: fn(ComponentType) -> bool,
    ) -> Result<(Vec<T>, usize)> {
        let doc = self.doc;
        let json = &doc.as_json().accessors[index];
        let here = format!("{at} (accessors[{index}])");
        let (Checked::Valid(ty), Checked::Valid(comp)) = (&json.type_, &json.component_type) else {
            return Err(GltfError::new(here, "invalid type or componentType"));
        };
        let comp = comp.0;
        let n = dims(*ty).filter(|n| dims_ok.contains(n)).ok_or_else(|| {
            GltfError::new(
                &here,
                format!("type {ty:?} is not one this attribute takes ({dims_ok:?} components)"),
            )
        })?;
        if !accept(comp) {
            return Err(GltfError::new(
                &here,
                format!("componentType {comp:?} is not one this attribute takes"),
            ));
        }
        let count = json.count.0 as usize;
        if count > MAX_ELEMENTS {
            return Err(GltfError::new(
                &here,
                format!("count {count} is more than the {MAX_ELEMENTS} elements read"),
            ));
        }
        self.take(&here, (count * n * std::mem::size_of::<T>()) as u64)?;
        let elem = size(comp) * n;
        let accessor = doc.accessors().nth(index).expect("validated index");
        let mut values = match accessor.view() {
            None => vec![T::default(); count * n],
            Some(view) => {
                let stride = view.stride().unwrap_or(elem);
                let offset = accessor.offset();
                let span = self.span(view, offset, stride, elem, count, &here)?;
                decode(&span, stride, elem, count, n, comp, json.normalized)
            }
        };
        if let Some(sparse) = &json.sparse {
            self.sparse(sparse, &mut values, count, n, comp, json.normalized, &here)?;
        }
        Ok((values, n))
    }

    /// The bytes `count` elements of `elem` bytes every `stride` from `offset` in `view`
    /// take, checked to lie inside the view.
    fn span(
        &mut self,
        view: gltf::buffer::View,
        offset: usize,
        stride: usize,
        elem: usize,
        count: usize,
        at: &str,
    ) -> Result<Span> {
        if stride < elem {
            return Err(GltfError::new(
                format!("bufferViews[{}].byteStride", view.index()),
                format!("byteStride {stride} is less than an element's {elem} bytes ({at})"),
            ));
        }
        let (buffer, range) = self.buffers.view(view.clone())?;
        // In u64 with checks: offsets and counts come from the file.
        let end = (offset as u64).checked_add(elem as u64);
        let need = match count {
            0 => Some(offset as u64),
            _ => (count as u64 - 1)
                .checked_mul(stride as u64)
                .and_then(|v| v.checked_add(end?)),
        };
        match need.filter(|&need| need <= range.len() as u64) {
            Some(_) => Ok(Span {
                buffer,
                range: range.start + offset..range.end,
            }),
            None => Err(GltfError::new(
                at,
                format!(
                    "{count} elements of {elem} bytes every {stride} from byte {offset} do not fit \
                     in bufferViews[{}] ({} bytes)",
                    view.index(),
                    range.len()
                ),
            )),
        }
    }

    /// Applies a sparse accessor's substitutions to `values`.
    #[allow(clippy::too_many_arguments)]
    fn sparse<T: Component>(
        &mut self,
        sparse: &gltf::json::accessor::sparse::Sparse,
        values: &mut [T],
        count: usize,
        n: usize,
        comp: ComponentType,
        normalized: bool,
        at: &str,
    ) -> Result<()> {
        let doc = self.doc;
        let k = sparse.count.0 as usize;
        let at = format!("{at}.sparse");
        let index_type = match &sparse.indices.component_type {
            Checked::Valid(c) => Some(c.0),
            Checked::Invalid => None,
        };
        let index_type = index_type
            .filter(|c| {
                matches!(
                    c,
                    ComponentType::U8 | ComponentType::U16 | ComponentType::U32
                )
            })
            .ok_or_else(|| {
                GltfError::new(
                    format!("{at}.indices.componentType"),
                    "sparse indices must be unsigned bytes, shorts or ints",
                )
            })?;
        let view_of = |i: gltf::json::Index<gltf::json::buffer::View>| {
            doc.views().nth(i.value()).expect("validated index")
        };
        let isize = size(index_type);
        let indices = self.span(
            view_of(sparse.indices.buffer_view),
            sparse.indices.byte_offset.0 as usize,
            isize,
            isize,
            k,
            &format!("{at}.indices"),
        )?;
        let elem = size(comp) * n;
        let subs = self.span(
            view_of(sparse.values.buffer_view),
            sparse.values.byte_offset.0 as usize,
            elem,
            elem,
            k,
            &format!("{at}.values"),
        )?;
        let indices: Vec<u32> = decode(&indices, isize, isize, k, 1, index_type, false);
        let subs: Vec<T> = decode(&subs, elem, elem, k, n, comp, normalized);
        for (j, &i) in indices.iter().enumerate() {
            let i = i as usize;
            if i >= count {
                return Err(GltfError::new(
                    format!("{at}.indices"),
                    format!("index {j} is {i}, past the accessor's {count} elements"),
                ));
            }
            values[i * n..(i + 1) * n].copy_from_slice(&subs[j * n..(j + 1) * n]);
        }
        Ok(())
    }
}

/// `count` elements of `n` components of type `comp`, every `stride` bytes of `span` (checked
/// to hold them).
fn decode<T: Component>(
    span: &Span,
    stride: usize,
    elem: usize,
    count: usize,
    n: usize,
    comp: ComponentType,
    normalized: bool,
) -> Vec<T> {
    let bytes = &span.buffer[span.range.clone()];
    let c = size(comp);
    let mut out = Vec::with_capacity(count * n);
    for i in 0..count {
        let e = &bytes[i * stride..i * stride + elem];
        out.extend(e.chunks_exact(c).map(|b| T::decode(b, comp, normalized)));
    }
    out
}
