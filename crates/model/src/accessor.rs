//! Reading accessors (glTF 2.0, section 3.6.2) with every claim checked
//! first: the element type, the buffer view and its buffer, the byte
//! offset, the stride and the count, in checked arithmetic; sparse
//! substitutions likewise. Only then is the output allocated, at most as
//! many elements as the bytes checked can hold (or, for an accessor with no
//! buffer view, as the caller allows).

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::schema::{Accessor, BufferView};
use crate::{Model, schema};

/// A component type, by its glTF code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Component {
    I8,
    U8,
    I16,
    U16,
    U32,
    F32,
}

impl Component {
    fn of(code: u32) -> Option<Self> {
        Some(match code {
            5120 => Self::I8,
            5121 => Self::U8,
            5122 => Self::I16,
            5123 => Self::U16,
            5125 => Self::U32,
            5126 => Self::F32,
            _ => return None,
        })
    }

    fn bytes(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::U32 | Self::F32 => 4,
        }
    }

    /// The value at the start of `b` as a float: normalised integers by the
    /// rules of section 3.11 (`max(c / 127, -1)` and the like), others as
    /// they are.
    fn float(self, b: &[u8], normalized: bool) -> f32 {
        let n = |x: f32, max: f32| if normalized { (x / max).max(-1.0) } else { x };
        match self {
            Self::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            Self::I8 => n(f32::from(b[0] as i8), 127.0),
            Self::U8 => n(f32::from(b[0]), 255.0),
            Self::I16 => n(f32::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
            Self::U16 => n(f32::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
            Self::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }

    /// The value at the start of `b` as an unsigned integer (indices).
    fn unsigned(self, b: &[u8]) -> Option<u32> {
        Some(match self {
            Self::U8 => u32::from(b[0]),
            Self::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            Self::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            _ => return None,
        })
    }
}

/// Checked elements of `count` elements of `element` bytes, `stride` apart,
/// from the start of `data`.
struct Strided<'a> {
    data: &'a [u8],
    stride: usize,
    count: usize,
}

impl Strided<'_> {
    fn element(&self, i: usize) -> &[u8] {
        &self.data[i * self.stride..]
    }
}

/// Elements per rayon task: fewer are decoded on one thread.
const TASK_ELEMENTS: usize = 16 * 1024;

/// An accessor whose claims have been checked.
struct Checked<'a> {
    component: Component,
    normalized: bool,
    count: usize,
    /// `None`: no buffer view, every element zero (before sparse values).
    dense: Option<Strided<'a>>,
    sparse: Option<(Component, Strided<'a>, Strided<'a>)>,
}

impl<'a> Model<'a> {
    /// A buffer view's bytes, checked against its buffer.
    fn view_bytes(&self, index: usize, referrer: &str) -> Result<(&'a [u8], BufferView)> {
        let view: BufferView = self.entry("bufferViews", index, referrer)?;
        let at = format!("/bufferViews/{index}");
        if view.buffer >= self.count("buffers") {
            return Err(Error::invalid(
                format!("{at}/buffer"),
                format!(
                    "refers to buffer {}, and the model has {}",
                    view.buffer,
                    self.count("buffers")
                ),
            ));
        }
        // Only the first buffer can exist (the others would need URIs).
        let buffer = self.bin;
        let bytes = view
            .byte_offset
            .checked_add(view.byte_length)
            .filter(|&end| end <= buffer.len() as u64)
            .map(|end| &buffer[view.byte_offset as usize..end as usize])
            .ok_or_else(|| {
                Error::invalid(
                    format!("{at}/byteLength"),
                    format!(
                        "the buffer view's {} bytes from byte {} run past its buffer's {} bytes",
                        view.byte_length,
                        view.byte_offset,
                        buffer.len()
                    ),
                )
            })?;
        Ok((bytes, view))
    }

    /// `count` elements of `element` bytes in buffer view `view_index`
    /// from `offset`, `stride` apart (the view's own, or packed).
    #[allow(clippy::too_many_arguments)]
    fn strided(
        &self,
        view_index: usize,
        referrer: &str,
        offset: u64,
        element: usize,
        count: u64,
        count_at: &str,
        packed: bool,
    ) -> Result<Strided<'a>> {
        let (bytes, view) = self.view_bytes(view_index, referrer)?;
        let stride = match view.byte_stride {
            Some(stride) if !packed => {
                if !(4..=252).contains(&stride)
                    || !stride.is_multiple_of(4)
                    || stride < element as u64
                {
                    return Err(Error::invalid(
                        format!("/bufferViews/{view_index}/byteStride"),
                        format!(
                            "a byteStride of {stride}: it must be a multiple of 4 from 4 to \
                             252, and at least the element's {element} bytes"
                        ),
                    ));
                }
                stride
            }
            _ => element as u64,
        };
        // The last element ends at offset + stride·(count − 1) + element.
        let end = count
            .checked_sub(1)
            .and_then(|last| last.checked_mul(stride))
            .and_then(|span| span.checked_add(offset))
            .and_then(|start| start.checked_add(element as u64));
        let Some(end) = end else {
            return Err(Error::invalid(
                count_at,
                format!(
                    "{count} elements of stride {stride} from byte {offset}: the size \
                     overflows (or the count is 0)"
                ),
            ));
        };
        if end > bytes.len() as u64 {
            return Err(Error::invalid(
                count_at,
                format!(
                    "{count} elements of {element} bytes, {stride} apart from byte {offset}, \
                     end at byte {end}, past the {} bytes of buffer view {view_index}",
                    bytes.len()
                ),
            ));
        }
        Ok(Strided {
            data: &bytes[offset as usize..end as usize],
            stride: stride as usize,
            count: count as usize,
        })
    }

    /// Accessor `index` checked: of type `kind` and of a component type
    /// `allowed` accepts, its bytes within its buffer view; `max_count`
    /// bounds one without a buffer view (413).
    fn checked(
        &self,
        index: usize,
        referrer: &str,
        kind: &str,
        allowed: impl Fn(Component, bool) -> bool,
        max_count: usize,
    ) -> Result<Checked<'a>> {
        let accessor: Accessor = self.entry("accessors", index, referrer)?;
        let at = format!("/accessors/{index}");
        let components = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => unreachable!("glint reads SCALAR, VEC3 and VEC4 accessors"),
        };
        if accessor.kind != kind {
            return Err(Error::invalid(
                format!("{at}/type"),
                format!("a {} accessor where a {kind} one belongs", accessor.kind),
            ));
        }
        let component = Component::of(accessor.component_type)
            .filter(|&c| allowed(c, accessor.normalized))
            .ok_or_else(|| {
                Error::invalid(
                    format!("{at}/componentType"),
                    format!(
                        "component type {}{} is not one this attribute may have",
                        accessor.component_type,
                        if accessor.normalized {
                            " (normalized)"
                        } else {
                            ""
                        }
                    ),
                )
            })?;
        let count_at = format!("{at}/count");
        if accessor.count == 0 {
            return Err(Error::invalid(
                count_at,
                "an accessor has at least 1 element",
            ));
        }
        let element = components * component.bytes();
        let dense = match accessor.buffer_view {
            Some(view) => Some(self.strided(
                view,
                &format!("{at}/bufferView"),
                accessor.byte_offset,
                element,
                accessor.count,
                &count_at,
                false,
            )?),
            None => {
                // Zeros: nothing holds the count but the caller's limit.
                if accessor.count > max_count as u64 {
                    return Err(Error::over_limit(
                        count_at,
                        format!(
                            "an accessor without a buffer view claims {} elements, over the \
                             {max_count} allowed here",
                            accessor.count
                        ),
                    ));
                }
                None
            }
        };
        let count = accessor.count as usize;
        let sparse = match &accessor.sparse {
            None => None,
            Some(sparse) => Some(self.sparse(&at, sparse, count, element)?),
        };
        Ok(Checked {
            component,
            normalized: accessor.normalized,
            count,
            dense,
            sparse,
        })
    }

    fn sparse(
        &self,
        at: &str,
        sparse: &schema::Sparse,
        count: usize,
        element: usize,
    ) -> Result<(Component, Strided<'a>, Strided<'a>)> {
        let at = format!("{at}/sparse");
        if sparse.count == 0 || sparse.count > count as u64 {
            return Err(Error::invalid(
                format!("{at}/count"),
                format!(
                    "{} sparse substitutions in an accessor of {count} elements",
                    sparse.count
                ),
            ));
        }
        let indices_at = format!("{at}/indices");
        let index_component = Component::of(sparse.indices.component_type)
            .filter(|c| matches!(c, Component::U8 | Component::U16 | Component::U32))
            .ok_or_else(|| {
                Error::invalid(
                    format!("{indices_at}/componentType"),
                    "sparse indices are unsigned bytes, shorts or ints",
                )
            })?;
        let indices = self.strided(
            sparse.indices.buffer_view,
            &format!("{indices_at}/bufferView"),
            sparse.indices.byte_offset,
            index_component.bytes(),
            sparse.count,
            &format!("{at}/count"),
            true,
        )?;
        let values = self.strided(
            sparse.values.buffer_view,
            &format!("{at}/values/bufferView"),
            sparse.values.byte_offset,
            element,
            sparse.count,
            &format!("{at}/count"),
            true,
        )?;
        let mut previous = None;
        for k in 0..indices.count {
            let i = index_component
                .unsigned(indices.element(k))
                .expect("an unsigned component");
            if previous.is_some_and(|p| i <= p) || i as usize >= count {
                return Err(Error::invalid(
                    indices_at,
                    format!(
                        "sparse index {k} is {i}: they must increase strictly and stay below \
                         the accessor's {count} elements"
                    ),
                ));
            }
            previous = Some(i);
        }
        Ok((index_component, indices, values))
    }

    /// A VEC3 accessor of floats (normalised integers allowed), every value
    /// finite, each element mapped by `f`: decoded and mapped in one pass,
    /// in parallel for batches worth it.
    pub(crate) fn vec3s<T: Send>(
        &self,
        index: usize,
        referrer: &str,
        max_count: usize,
        f: impl Fn([f32; 3]) -> T + Sync,
    ) -> Result<Vec<T>> {
        let checked = self.checked(
            index,
            referrer,
            "VEC3",
            |c, normalized| c == Component::F32 || normalized && c != Component::U32,
            max_count,
        )?;
        let (c, normalized) = (checked.component, checked.normalized);
        let read = |b: &[u8]| {
            if c == Component::F32 {
                let f = |o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
                [f(0), f(4), f(8)]
            } else {
                let size = c.bytes();
                [0, 1, 2].map(|k| c.float(&b[k * size..], normalized))
            }
        };
        let finite = |v: &[f32; 3]| v.iter().all(|x| x.is_finite());
        let not_finite = |k: usize, v: [f32; 3]| {
            Error::invalid(
                format!("/accessors/{index}"),
                format!("element {k} is {v:?}: numbers must be finite"),
            )
        };
        let value = |i: usize| match &checked.dense {
            Some(dense) => read(dense.element(i)),
            None => [0.0; 3],
        };
        if let Some((index_component, indices, values)) = &checked.sparse {
            // Rare: the values whole, substituted, then checked and mapped.
            let mut raw: Vec<[f32; 3]> = (0..checked.count).map(value).collect();
            for k in 0..indices.count {
                let i = index_component
                    .unsigned(indices.element(k))
                    .expect("unsigned");
                raw[i as usize] = read(values.element(k));
            }
            if let Some(k) = raw.iter().position(|v| !finite(v)) {
                return Err(not_finite(k, raw[k]));
            }
            return Ok(raw.into_iter().map(f).collect());
        }
        let first_bad = AtomicUsize::new(usize::MAX);
        let out = (0..checked.count)
            .into_par_iter()
            .with_min_len(TASK_ELEMENTS)
            .map(|i| {
                let v = value(i);
                if !finite(&v) {
                    first_bad.fetch_min(i, Ordering::Relaxed);
                }
                f(v)
            })
            .collect();
        match first_bad.into_inner() {
            usize::MAX => Ok(out),
            k => Err(not_finite(k, value(k))),
        }
    }

    /// The `COLOR_0` of an instance's primitive, RGBA (alpha 1 for a VEC3
    /// accessor), `None` where it has none: floats or normalised unsigned
    /// bytes or shorts (glTF 2.0, section 3.7.2.1), one per vertex, every
    /// value finite.
    pub fn colors(&self, instance: &crate::Instance) -> Result<Option<Vec<[f32; 4]>>> {
        let at = format!(
            "/meshes/{}/primitives/{}",
            instance.mesh, instance.primitive
        );
        let primitive: schema::Primitive = self.get(&at)?;
        let Some(&index) = primitive.attributes.get("COLOR_0") else {
            return Ok(None);
        };
        let referrer = format!("{at}/attributes/COLOR_0");
        let accessor: Accessor = self.entry("accessors", index, &referrer)?;
        let kind = match accessor.kind.as_str() {
            kind @ ("VEC3" | "VEC4") => kind,
            other => {
                return Err(Error::invalid(
                    format!("/accessors/{index}/type"),
                    format!("a {other} accessor as COLOR_0, which is VEC3 or VEC4"),
                ));
            }
        };
        let vertices = instance.positions.len();
        let checked = self.checked(
            index,
            &referrer,
            kind,
            |c, normalized| {
                c == Component::F32 || normalized && matches!(c, Component::U8 | Component::U16)
            },
            vertices,
        )?;
        if checked.count != vertices {
            return Err(Error::invalid(
                format!("/accessors/{index}/count"),
                format!(
                    "{} colours in COLOR_0 for the primitive's {vertices} vertices",
                    checked.count
                ),
            ));
        }
        let (c, normalized) = (checked.component, checked.normalized);
        let channels = if kind == "VEC4" { 4 } else { 3 };
        let read = |b: &[u8]| -> [f32; 4] {
            let size = c.bytes();
            std::array::from_fn(|k| {
                if k < channels {
                    c.float(&b[k * size..], normalized)
                } else {
                    1.0
                }
            })
        };
        let mut colors: Vec<[f32; 4]> = match &checked.dense {
            Some(dense) => (0..dense.count)
                .into_par_iter()
                .with_min_len(TASK_ELEMENTS)
                .map(|i| read(dense.element(i)))
                .collect(),
            None => vec![[0.0, 0.0, 0.0, 1.0]; checked.count],
        };
        if let Some((index_component, indices, values)) = &checked.sparse {
            for k in 0..indices.count {
                let i = index_component
                    .unsigned(indices.element(k))
                    .expect("unsigned");
                colors[i as usize] = read(values.element(k));
            }
        }
        if let Some(k) = colors
            .par_iter()
            .position_first(|v| !v.iter().all(|x| x.is_finite()))
        {
            return Err(Error::invalid(
                format!("/accessors/{index}"),
                format!("element {k} is {:?}: colours must be finite", colors[k]),
            ));
        }
        Ok(Some(colors))
    }

    /// A SCALAR accessor of unsigned integers (indices), checked.
    fn indices(&self, index: usize, referrer: &str, max_count: usize) -> Result<Checked<'a>> {
        self.checked(
            index,
            referrer,
            "SCALAR",
            |c, normalized| {
                !normalized && matches!(c, Component::U8 | Component::U16 | Component::U32)
            },
            max_count,
        )
    }

    /// A SCALAR accessor of unsigned integers (indices).
    pub(crate) fn unsigned(
        &self,
        index: usize,
        referrer: &str,
        max_count: usize,
    ) -> Result<Vec<u32>> {
        let checked = self.indices(index, referrer, max_count)?;
        let c = checked.component;
        let read = |b: &[u8]| c.unsigned(b).expect("an unsigned component");
        let mut out: Vec<u32> = match &checked.dense {
            Some(dense) => (0..dense.count)
                .into_par_iter()
                .with_min_len(TASK_ELEMENTS)
                .map(|i| read(dense.element(i)))
                .collect(),
            None => vec![0; checked.count],
        };
        if let Some((index_component, indices, values)) = &checked.sparse {
            for k in 0..indices.count {
                let i = index_component
                    .unsigned(indices.element(k))
                    .expect("unsigned");
                out[i as usize] = read(values.element(k));
            }
        }
        Ok(out)
    }

    /// The number of elements of a SCALAR accessor of unsigned integers
    /// and the largest of them, read without allocating.
    pub(crate) fn unsigned_count_max(
        &self,
        index: usize,
        referrer: &str,
        max_count: usize,
    ) -> Result<(usize, u32)> {
        let checked = self.indices(index, referrer, max_count)?;
        if checked.sparse.is_some() {
            let all = self.unsigned(index, referrer, max_count)?;
            return Ok((all.len(), all.iter().copied().max().unwrap_or(0)));
        }
        let max = match &checked.dense {
            // In blocks of whole elements, each read by a loop of its
            // component type.
            Some(dense) => dense
                .data
                .par_chunks(TASK_ELEMENTS * dense.stride)
                .map(|block| {
                    let elements = block.chunks(dense.stride);
                    match checked.component {
                        Component::U8 => elements.map(|b| u32::from(b[0])).max(),
                        Component::U16 => elements
                            .map(|b| u32::from(u16::from_le_bytes([b[0], b[1]])))
                            .max(),
                        _ => elements
                            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                            .max(),
                    }
                    .unwrap_or(0)
                })
                .max()
                .unwrap_or(0),
            None => 0,
        };
        Ok((checked.count, max))
    }
}
