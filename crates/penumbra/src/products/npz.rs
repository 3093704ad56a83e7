//! NumPy's `.npz` as `numpy.savez` writes it: each array a `.npy` file (format 1.0: a
//! little-endian array in C order after a header padded to 64 bytes) in an uncompressed ZIP,
//! which `numpy.load` reads back. Only what the AOVs need: float32 and uint32 arrays.

/// An array's element type and values, in C order.
#[derive(Clone, Debug, PartialEq)]
pub enum NpyData {
    /// `<f4`.
    F32(Vec<f32>),
    /// `<u4`.
    U32(Vec<u32>),
}

/// An n-dimensional array for an `.npz`.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// Its shape, outermost first; the product is the number of values.
    pub shape: Vec<usize>,
    /// Its values.
    pub data: NpyData,
}

impl NpyArray {
    fn len(&self) -> usize {
        match &self.data {
            NpyData::F32(v) => v.len(),
            NpyData::U32(v) => v.len(),
        }
    }

    /// The `.npy` file of the array.
    fn npy(&self) -> Vec<u8> {
        let descr = match self.data {
            NpyData::F32(_) => "<f4",
            NpyData::U32(_) => "<u4",
        };
        let shape = match self.shape.as_slice() {
            [n] => format!("({n},)"),
            dims => {
                let d: Vec<String> = dims.iter().map(usize::to_string).collect();
                format!("({})", d.join(", "))
            }
        };
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        // Magic (6), version (2), length (2), the header and its newline: a multiple of 64.
        let pad = (64 - (10 + header.len() + 1) % 64) % 64;
        header.push_str(&" ".repeat(pad));
        header.push('\n');
        let mut out = Vec::with_capacity(10 + header.len() + 4 * self.len());
        out.extend_from_slice(b"\x93NUMPY\x01\x00");
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        match &self.data {
            NpyData::F32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::U32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        }
        out
    }
}

/// The `.npz` of `arrays` (`NAME.npy` each, in order); an error for an array whose shape
/// does not hold its values, or a file beyond a ZIP's 4 GiB without ZIP64.
pub fn npz_bytes(arrays: &[(String, NpyArray)]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, array) in arrays {
        if array.shape.iter().product::<usize>() != array.len() {
            return Err(format!(
                "array {name:?} has {} values, not the {} of its shape {:?}",
                array.len(),
                array.shape.iter().product::<usize>(),
                array.shape
            ));
        }
        let file = array.npy();
        let name = format!("{name}.npy");
        let too_large = || "the arrays are too large for a .npz without ZIP64".to_owned();
        let size = u32::try_from(file.len()).map_err(|_| too_large())?;
        let offset = u32::try_from(out.len()).map_err(|_| too_large())?;
        let crc = crc32(&file);
        // The fields shared by the local and the central header: version 2.0, no flags,
        // stored, 1980-01-01 00:00, the CRC and both sizes, the name's length.
        let mut common = Vec::new();
        for v in [20u16, 0, 0, 0, 0x21] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        for v in [crc, size, size] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        common.extend_from_slice(&(name.len() as u16).to_le_bytes());
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        out.extend_from_slice(&common);
        out.extend_from_slice(&0u16.to_le_bytes()); // no extra field
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(&file);
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&20u16.to_le_bytes()); // made by version 2.0
        central.extend_from_slice(&common);
        for v in [0u16, 0, 0, 0] {
            central.extend_from_slice(&v.to_le_bytes()); // extra, comment, disk, internal
        }
        central.extend_from_slice(&(0o100644u32 << 16).to_le_bytes()); // a regular file
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let too_large = |_| "the arrays are too large for a .npz without ZIP64".to_owned();
    let entries = u16::try_from(arrays.len()).map_err(|_| "too many arrays".to_owned())?;
    let (cd_size, cd_offset) = (
        u32::try_from(central.len()).map_err(too_large)?,
        u32::try_from(out.len()).map_err(too_large)?,
    );
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    for v in [0u16, 0, entries, entries] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&cd_size.to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    Ok(out)
}

/// CRC-32 (IEEE 802.3, reflected, as ZIP uses it).
fn crc32(bytes: &[u8]) -> u32 {
    const TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
                k += 1;
            }
            table[i] = c;
            i += 1;
        }
        table
    };
    !bytes.iter().fold(!0u32, |c, &b| {
        TABLE[((c ^ u32::from(b)) & 0xFF) as usize] ^ (c >> 8)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_crc_is_zips() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn an_npy_header_is_padded_to_64_bytes() {
        let a = NpyArray {
            shape: vec![2, 3],
            data: NpyData::U32(vec![1, 2, 3, 4, 5, 6]),
        };
        let npy = a.npy();
        let header_len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        let header = std::str::from_utf8(&npy[10..10 + header_len]).unwrap();
        assert!(header.starts_with("{'descr': '<u4', 'fortran_order': False, 'shape': (2, 3), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(npy.len(), 10 + header_len + 24);
        let bad = NpyArray {
            shape: vec![4],
            ..a
        };
        assert!(npz_bytes(&[("x".into(), bad)])
            .unwrap_err()
            .contains("shape"));
        let zip = npz_bytes(&[(
            "depth".into(),
            NpyArray {
                shape: vec![1],
                data: NpyData::F32(vec![1.5]),
            },
        )])
        .unwrap();
        assert_eq!(&zip[..4], b"PK\x03\x04");
        assert_eq!(&zip[zip.len() - 22..zip.len() - 18], b"PK\x05\x06");
    }
}
