//! CDR (OMG XCDR1, little endian) as ROS 2 writes messages: a 4-byte encapsulation header, then
//! each primitive aligned to its own size counted from the end of that header; strings as a
//! `u32` length that includes the terminating NUL, the bytes and the NUL; sequences as a `u32`
//! count and their elements.

/// The encapsulation header of little-endian plain CDR (`CDR_LE`).
pub const CDR_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Writes one CDR message.
pub struct CdrWriter<'a> {
    out: &'a mut Vec<u8>,
    /// Where the payload starts (alignment is counted from here).
    origin: usize,
}

impl<'a> CdrWriter<'a> {
    /// Starts a message at the end of `out`, with its encapsulation header.
    pub fn new(out: &'a mut Vec<u8>) -> Self {
        out.extend_from_slice(&CDR_LE);
        let origin = out.len();
        CdrWriter { out, origin }
    }

    fn align(&mut self, size: usize) {
        let pos = self.out.len() - self.origin;
        let pad = (size - pos % size) % size;
        self.out.resize(self.out.len() + pad, 0);
    }

    /// An `uint8`/`byte`.
    pub fn u8(&mut self, v: u8) {
        self.out.push(v);
    }

    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    /// An `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32`.
    pub fn f32(&mut self, v: f32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    /// A `string`: length with the NUL, bytes, NUL.
    pub fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.out.extend_from_slice(s.as_bytes());
        self.out.push(0);
    }

    /// A `float32[]`.
    pub fn f32_seq(&mut self, values: impl ExactSizeIterator<Item = f32>) {
        self.u32(values.len() as u32);
        for v in values {
            self.out.extend_from_slice(&v.to_le_bytes());
        }
    }

    /// A `uint8[]` or `int8[]` (as bytes).
    pub fn bytes(&mut self, bytes: &[u8]) {
        self.u32(bytes.len() as u32);
        self.out.extend_from_slice(bytes);
    }
}

/// Reads one CDR message; every read says what it expected when the message ends too soon.
pub struct CdrReader<'a> {
    data: &'a [u8],
    pos: usize,
}

/// Offsets in reader errors count from the start of the message (the encapsulation header).
const HEADER: usize = 4;

impl<'a> CdrReader<'a> {
    /// Checks the encapsulation header (little-endian CDR only).
    pub fn new(data: &'a [u8]) -> Result<Self, String> {
        match data.get(..HEADER) {
            Some([0x00, 0x01, _, _]) => Ok(CdrReader {
                data: &data[HEADER..],
                pos: 0,
            }),
            Some(h) => Err(format!(
                "expected the CDR_LE encapsulation header 00 01, got {:02x} {:02x}",
                h[0], h[1]
            )),
            None => Err("expected a 4-byte CDR encapsulation header".into()),
        }
    }

    fn take(&mut self, size: usize, align: usize, what: &str) -> Result<&'a [u8], String> {
        let pad = (align - self.pos % align) % align;
        let start = self.pos + pad;
        let end = start.checked_add(size).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(format!(
                "expected {what} ({size} bytes) at byte {}, the message ends at {}",
                start + HEADER,
                self.data.len() + HEADER
            ));
        };
        self.pos = end;
        Ok(&self.data[start..end])
    }

    /// An `uint8`.
    pub fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, 1, what)?[0])
    }

    /// An `int32`.
    pub fn i32(&mut self, what: &str) -> Result<i32, String> {
        Ok(i32::from_le_bytes(
            self.take(4, 4, what)?.try_into().unwrap(),
        ))
    }

    /// An `uint32`.
    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4, 4, what)?.try_into().unwrap(),
        ))
    }

    /// A `float32`.
    pub fn f32(&mut self, what: &str) -> Result<f32, String> {
        Ok(f32::from_le_bytes(
            self.take(4, 4, what)?.try_into().unwrap(),
        ))
    }

    /// A `float64`.
    pub fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8, 8, what)?.try_into().unwrap(),
        ))
    }

    /// A `string` (its NUL checked and dropped).
    pub fn string(&mut self, what: &str) -> Result<String, String> {
        let len = self.u32(what)? as usize;
        let bytes = self.take(len, 1, what)?;
        match bytes.split_last() {
            Some((0, text)) => String::from_utf8(text.to_vec())
                .map_err(|_| format!("expected {what} as UTF-8 text")),
            _ => Err(format!("expected {what} to end with a NUL byte")),
        }
    }

    /// A `float32[]`.
    pub fn f32_seq(&mut self, what: &str) -> Result<Vec<f32>, String> {
        let n = self.u32(what)? as usize;
        let bytes = self.take(n.saturating_mul(4), 4, what)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect())
    }

    /// A `uint8[]` or `int8[]`.
    pub fn bytes(&mut self, what: &str) -> Result<&'a [u8], String> {
        let n = self.u32(what)? as usize;
        self.take(n, 1, what)
    }
}
