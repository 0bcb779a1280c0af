//! The protobuf wire format, for the few fields of the Foxglove messages petrel writes in
//! binary: a writer into a reused buffer (bytes fields copied once, never as text) and a reader
//! that says at which offset a message stops making sense. Hand-written because the messages
//! are small and fixed; the tests check it against `prost-reflect`, a decoder of its own.

/// Wire type of varints (integers, enums, bools).
pub const VARINT: u8 = 0;
/// Wire type of 64-bit fixed fields (`double`, `fixed64`).
pub const FIXED64: u8 = 1;
/// Wire type of length-delimited fields (strings, bytes, messages, packed repeated fields).
pub const LEN: u8 = 2;
/// Wire type of 32-bit fixed fields (`fixed32`, `float`).
pub const FIXED32: u8 = 5;

/// Appends `v` as a varint.
pub fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// Appends the key of field `field` of wire type `wire`.
pub fn key(out: &mut Vec<u8>, field: u32, wire: u8) {
    varint(out, (u64::from(field) << 3) | u64::from(wire));
}

/// Appends a varint field (proto3: a zero is not written).
pub fn uint(out: &mut Vec<u8>, field: u32, v: u64) {
    if v != 0 {
        key(out, field, VARINT);
        varint(out, v);
    }
}

/// Appends a `fixed32` field (proto3: a zero is not written).
pub fn fixed32(out: &mut Vec<u8>, field: u32, v: u32) {
    if v != 0 {
        key(out, field, FIXED32);
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// Appends a `double` field (proto3: a zero is not written; -0.0 is, to keep its sign).
pub fn double(out: &mut Vec<u8>, field: u32, v: f64) {
    if v.to_bits() != 0 {
        key(out, field, FIXED64);
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// Appends a `bytes` or `string` field (proto3: an empty one is not written).
pub fn bytes(out: &mut Vec<u8>, field: u32, v: &[u8]) {
    if !v.is_empty() {
        key(out, field, LEN);
        varint(out, v.len() as u64);
        out.extend_from_slice(v);
    }
}

/// Appends a packed `repeated double` field.
pub fn doubles(out: &mut Vec<u8>, field: u32, v: &[f64]) {
    if !v.is_empty() {
        key(out, field, LEN);
        varint(out, (v.len() * 8) as u64);
        out.reserve(v.len() * 8);
        for x in v {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// Appends a message field whose content `body` writes; its length is patched in after
/// (one byte reserved: the nested messages petrel writes are short, a longer one is moved).
pub fn message(out: &mut Vec<u8>, field: u32, body: impl FnOnce(&mut Vec<u8>)) {
    key(out, field, LEN);
    let at = out.len();
    out.push(0);
    body(out);
    let len = out.len() - at - 1;
    if len < 0x80 {
        out[at] = len as u8;
    } else {
        let mut prefix = Vec::with_capacity(10);
        varint(&mut prefix, len as u64);
        out.splice(at..=at, prefix);
    }
}

/// One field's value as the wire carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value<'a> {
    /// A varint.
    Varint(u64),
    /// 8 bytes, little-endian.
    Fixed64(u64),
    /// Length-delimited bytes.
    Len(&'a [u8]),
    /// 4 bytes, little-endian.
    Fixed32(u32),
}

impl<'a> Value<'a> {
    /// As a `double`.
    pub fn f64(self) -> Result<f64, String> {
        match self {
            Value::Fixed64(bits) => Ok(f64::from_bits(bits)),
            other => Err(format!("expected a double, got {other:?}")),
        }
    }

    /// As a `fixed32`.
    pub fn u32(self) -> Result<u32, String> {
        match self {
            Value::Fixed32(v) => Ok(v),
            other => Err(format!("expected a fixed32, got {other:?}")),
        }
    }

    /// As a varint.
    pub fn varint(self) -> Result<u64, String> {
        match self {
            Value::Varint(v) => Ok(v),
            other => Err(format!("expected a varint, got {other:?}")),
        }
    }

    /// As length-delimited bytes (a string, bytes, a message, a packed field).
    pub fn len(self) -> Result<&'a [u8], String> {
        match self {
            Value::Len(b) => Ok(b),
            other => Err(format!("expected length-delimited bytes, got {other:?}")),
        }
    }
}

/// Reads the fields of one message in order; every error names the offset.
pub struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// A reader of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Reader { data, at: 0 }
    }

    fn read_varint(&mut self) -> Result<u64, String> {
        let start = self.at;
        let mut v = 0_u64;
        for shift in (0..64).step_by(7) {
            let Some(&b) = self.data.get(self.at) else {
                return Err(format!("at byte {start}: expected a varint, got the end"));
            };
            self.at += 1;
            v |= u64::from(b & 0x7f) << shift;
            if b < 0x80 {
                return Ok(v);
            }
        }
        Err(format!(
            "at byte {start}: expected a varint of at most 10 bytes"
        ))
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(format!(
                "at byte {}: expected {n} bytes, {} left",
                self.at,
                self.data.len() - self.at
            ));
        };
        let bytes = &self.data[self.at..end];
        self.at = end;
        Ok(bytes)
    }

    /// The next field's number and value, or `None` at the end.
    pub fn field(&mut self) -> Result<Option<(u32, Value<'a>)>, String> {
        if self.at == self.data.len() {
            return Ok(None);
        }
        let start = self.at;
        let k = self.read_varint()?;
        let field = u32::try_from(k >> 3)
            .ok()
            .filter(|&f| f > 0)
            .ok_or_else(|| format!("at byte {start}: expected a field number, got {}", k >> 3))?;
        let value = match (k & 7) as u8 {
            VARINT => Value::Varint(self.read_varint()?),
            FIXED64 => Value::Fixed64(u64::from_le_bytes(self.take(8)?.try_into().unwrap())),
            LEN => {
                let n = self.read_varint()?;
                let n = usize::try_from(n).map_err(|_| format!("at byte {start}: length {n}"))?;
                Value::Len(self.take(n)?)
            }
            FIXED32 => Value::Fixed32(u32::from_le_bytes(self.take(4)?.try_into().unwrap())),
            w => {
                return Err(format!(
                    "at byte {start}: expected wire type 0, 1, 2 or 5, got {w}"
                ))
            }
        };
        Ok(Some((field, value)))
    }

    /// Calls `each` with every field until the end.
    pub fn each(
        mut self,
        mut each: impl FnMut(u32, Value<'a>) -> Result<(), String>,
    ) -> Result<(), String> {
        while let Some((field, value)) = self.field()? {
            each(field, value)?;
        }
        Ok(())
    }
}

/// The doubles of a packed `repeated double` field.
pub fn read_doubles(bytes: &[u8]) -> Result<Vec<f64>, String> {
    if bytes.len() % 8 != 0 {
        return Err(format!(
            "expected packed doubles (a multiple of 8 bytes), got {} bytes",
            bytes.len()
        ));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("chunks of 8")))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_round_trip_at_every_length() {
        for v in [
            0,
            1,
            127,
            128,
            300,
            16_383,
            16_384,
            u64::from(u32::MAX),
            u64::MAX,
        ] {
            let mut out = Vec::new();
            uint(&mut out, 3, v);
            let mut r = Reader::new(&out);
            match v {
                0 => assert_eq!(r.field().unwrap(), None),
                v => assert_eq!(r.field().unwrap(), Some((3, Value::Varint(v)))),
            }
            assert_eq!(r.field().unwrap(), None);
        }
    }

    #[test]
    fn a_long_nested_message_gets_a_longer_length() {
        let mut out = Vec::new();
        message(&mut out, 9, |o| bytes(o, 1, &[7; 300]));
        let mut r = Reader::new(&out);
        let (field, value) = r.field().unwrap().unwrap();
        assert_eq!(field, 9);
        let inner = value.len().unwrap();
        assert_eq!(inner.len(), 303);
        let mut r = Reader::new(inner);
        assert_eq!(r.field().unwrap(), Some((1, Value::Len(&[7; 300][..]))));
    }

    #[test]
    fn a_cut_message_names_the_offset() {
        let mut out = Vec::new();
        double(&mut out, 4, 1.5);
        bytes(&mut out, 9, &[1, 2, 3, 4]);
        let cut = &out[..out.len() - 2];
        let mut r = Reader::new(cut);
        assert_eq!(
            r.field().unwrap(),
            Some((4, Value::Fixed64(1.5_f64.to_bits())))
        );
        let err = r.field().unwrap_err();
        assert!(
            err.contains("at byte 11") && err.contains("expected 4 bytes"),
            "{err}"
        );
        let err = Reader::new(&[0x0f]).field().unwrap_err();
        assert!(err.contains("wire type"), "{err}");
        assert!(read_doubles(&[0; 12]).is_err());
    }
}
