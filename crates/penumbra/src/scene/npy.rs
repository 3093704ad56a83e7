//! Instance transforms from `.npy` files: NumPy's array format (versions 1 to 3), an array of
//! shape (N, 4, 4) of little-endian float32 or float64 in C order, as
//! `numpy.save("poses.npy", matrices)` writes it. Each matrix is row-major and maps object
//! space to world space (the last row is 0, 0, 0, 1), as trimesh and Open3D write transforms.

use glam::Mat4;
use thiserror::Error;

/// Why a `.npy` file holds no transforms penumbra can place.
#[derive(Debug, Error, PartialEq)]
pub(crate) enum NpyError {
    /// Not NumPy's format, or a header that does not parse.
    #[error("not a .npy file ({0})")]
    Format(&'static str),
    /// Another element type.
    #[error("the array holds {0}; transforms must be float32 or float64 ('<f4' or '<f8')")]
    Dtype(String),
    /// Fortran (column-major) order.
    #[error("the array is in Fortran order; save it in C order (numpy.ascontiguousarray)")]
    FortranOrder,
    /// Another shape.
    #[error("the array has shape {0}; transforms must have shape (N, 4, 4)")]
    Shape(String),
    /// Fewer bytes than the shape needs.
    #[error("the file ends before its {0} matrices do")]
    Truncated(usize),
    /// A matrix with a NaN or infinite entry.
    #[error("matrix {0} has an entry that is not a finite number")]
    NotFinite(usize),
    /// A matrix whose last row is not 0, 0, 0, 1.
    #[error("matrix {0} is not affine: its last row must be 0, 0, 0, 1")]
    NotAffine(usize),
}

/// What the header says: how many matrices, of which float, from which byte on.
#[derive(Debug, PartialEq)]
pub(crate) struct Header {
    pub count: usize,
    double: bool,
    data: usize,
}

/// Reads the header of `bytes`.
pub(crate) fn header(bytes: &[u8]) -> Result<Header, NpyError> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(NpyError::Format("it does not start with \\x93NUMPY"));
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        _ => return Err(NpyError::Format("unknown format version")),
    };
    let text = bytes
        .get(start..start.saturating_add(len))
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or(NpyError::Format("the header is cut short or not text"))?;
    let descr = quoted(value(text, "descr")?)?;
    let double = match descr {
        "<f4" => false,
        "<f8" => true,
        other => return Err(NpyError::Dtype(format!("'{other}'"))),
    };
    match value(text, "fortran_order")? {
        v if v.starts_with("False") => {}
        v if v.starts_with("True") => return Err(NpyError::FortranOrder),
        _ => return Err(NpyError::Format("fortran_order is neither True nor False")),
    }
    let shape = value(text, "shape")?;
    let close = shape
        .find(')')
        .ok_or(NpyError::Format("shape is not a tuple"))?;
    let dims: Vec<&str> = shape[..close]
        .trim_start_matches('(')
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .collect();
    let tuple = format!("({})", dims.join(", "));
    let count = match dims[..] {
        [n, "4", "4"] => n.parse().map_err(|_| NpyError::Shape(tuple))?,
        _ => return Err(NpyError::Shape(tuple)),
    };
    Ok(Header {
        count,
        double,
        data: start + len,
    })
}

/// The text after `'key':` in the header dictionary.
fn value<'a>(text: &'a str, key: &'static str) -> Result<&'a str, NpyError> {
    let at = text
        .find(&format!("'{key}':"))
        .ok_or(NpyError::Format("the header lacks a key"))?;
    Ok(text[at + key.len() + 3..].trim_start())
}

/// The string a quoted value starts with.
fn quoted(v: &str) -> Result<&str, NpyError> {
    let rest = v
        .strip_prefix('\'')
        .ok_or(NpyError::Format("descr is not a string"))?;
    let end = rest
        .find('\'')
        .ok_or(NpyError::Format("descr is not a string"))?;
    Ok(&rest[..end])
}

/// The matrices of `bytes` (whose header is `header`), checked finite and affine.
pub(crate) fn matrices(bytes: &[u8], header: &Header) -> Result<Vec<Mat4>, NpyError> {
    let size = if header.double { 8 } else { 4 };
    let need = header
        .count
        .checked_mul(16 * size)
        .ok_or(NpyError::Truncated(header.count))?;
    let data = bytes
        .get(header.data..)
        .filter(|d| d.len() >= need)
        .ok_or(NpyError::Truncated(header.count))?;
    let read = |k: usize| -> f64 {
        let b = &data[k * size..(k + 1) * size];
        if header.double {
            f64::from_le_bytes(b.try_into().expect("8 bytes"))
        } else {
            f32::from_le_bytes(b.try_into().expect("4 bytes")) as f64
        }
    };
    (0..header.count)
        .map(|i| {
            let rows: Vec<f64> = (0..16).map(|k| read(16 * i + k)).collect();
            if rows
                .iter()
                .any(|v| !v.is_finite() || v.abs() > f32::MAX as f64)
            {
                return Err(NpyError::NotFinite(i));
            }
            if rows[12..] != [0.0, 0.0, 0.0, 1.0] {
                return Err(NpyError::NotAffine(i));
            }
            let m: Vec<f32> = rows.iter().map(|&v| v as f32).collect();
            Ok(Mat4::from_cols_slice(&m).transpose())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version-1 file as numpy.save writes it.
    fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        npy_in_order(descr, "False", shape, data)
    }

    fn npy_in_order(descr: &str, fortran: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut text =
            format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}");
        while (10 + text.len() + 1) % 64 != 0 {
            text.push(' ');
        }
        text.push('\n');
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend((text.len() as u16).to_le_bytes());
        bytes.extend(text.as_bytes());
        bytes.extend(data);
        bytes
    }

    fn f32s(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    const TRANSLATE: [f32; 16] = [
        1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 1.0,
    ];

    #[test]
    fn row_major_matrices_map_object_to_world() {
        let bytes = npy("<f4", "(1, 4, 4)", &f32s(&TRANSLATE));
        let h = header(&bytes).unwrap();
        let m = matrices(&bytes, &h).unwrap();
        assert_eq!(
            m[0].transform_point3(glam::Vec3::ZERO),
            glam::Vec3::new(1.0, 2.0, 3.0)
        );
        let doubles: Vec<u8> = TRANSLATE
            .iter()
            .flat_map(|&v| (v as f64).to_le_bytes())
            .collect();
        let bytes = npy("<f8", "(1, 4, 4)", &doubles);
        assert_eq!(matrices(&bytes, &header(&bytes).unwrap()).unwrap(), m);
    }

    #[test]
    fn wrong_files_are_errors_naming_what_is_wrong() {
        let one = f32s(&TRANSLATE);
        let mut nan = TRANSLATE;
        nan[5] = f32::NAN;
        let mut projective = TRANSLATE;
        projective[14] = 0.5;
        let cases: [(Vec<u8>, NpyError); 7] = [
            (
                b"PK\x03\x04 not npy".to_vec(),
                NpyError::Format("it does not start with \\x93NUMPY"),
            ),
            (
                npy("<i8", "(1, 4, 4)", &one),
                NpyError::Dtype("'<i8'".into()),
            ),
            (
                npy("<f4", "(1, 3, 4)", &one),
                NpyError::Shape("(1, 3, 4)".into()),
            ),
            (npy("<f4", "(16,)", &one), NpyError::Shape("(16)".into())),
            (npy("<f4", "(2, 4, 4)", &one), NpyError::Truncated(2)),
            (npy("<f4", "(1, 4, 4)", &f32s(&nan)), NpyError::NotFinite(0)),
            (
                npy("<f4", "(1, 4, 4)", &f32s(&projective)),
                NpyError::NotAffine(0),
            ),
        ];
        for (bytes, expected) in cases {
            let got = header(&bytes).and_then(|h| matrices(&bytes, &h));
            assert_eq!(got, Err(expected));
        }
        let fortran = npy_in_order("<f4", "True", "(1, 4, 4)", &one);
        assert_eq!(header(&fortran), Err(NpyError::FortranOrder));
    }
}
