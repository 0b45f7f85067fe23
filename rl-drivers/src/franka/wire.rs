//! Little-endian readers and writers over byte slices for the packed records, bounds-checked by
//! their callers (each record checks its length once, then reads at fixed offsets).

/// A reader at an offset into a slice whose length the caller has checked.
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    /// The next `N` bytes; zeros past the end (never reached: callers check lengths first).
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.bytes.get(self.at..self.at + N) {
            out.copy_from_slice(s);
        }
        self.at += N;
        out
    }

    pub(crate) fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }

    pub(crate) fn bool(&mut self) -> bool {
        self.u8() != 0
    }

    pub(crate) fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }

    pub(crate) fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }

    pub(crate) fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }

    pub(crate) fn f32(&mut self) -> f64 {
        f64::from(f32::from_le_bytes(self.take()))
    }

    pub(crate) fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }

    pub(crate) fn f32s<const N: usize>(&mut self) -> [f64; N] {
        core::array::from_fn(|_| self.f32())
    }

    pub(crate) fn f64s<const N: usize>(&mut self) -> [f64; N] {
        core::array::from_fn(|_| self.f64())
    }

    pub(crate) fn bools<const N: usize>(&mut self) -> [bool; N] {
        core::array::from_fn(|_| self.bool())
    }

    pub(crate) fn position(&self) -> usize {
        self.at
    }
}

/// A writer into a slice whose length the caller has checked.
pub(crate) struct Writer<'a> {
    bytes: &'a mut [u8],
    at: usize,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(bytes: &'a mut [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    fn put(&mut self, b: &[u8]) {
        if let Some(s) = self.bytes.get_mut(self.at..self.at + b.len()) {
            s.copy_from_slice(b);
        }
        self.at += b.len();
    }

    pub(crate) fn u8(&mut self, v: u8) {
        self.put(&[v]);
    }

    pub(crate) fn bool(&mut self, v: bool) {
        self.u8(u8::from(v));
    }

    pub(crate) fn u16(&mut self, v: u16) {
        self.put(&v.to_le_bytes());
    }

    pub(crate) fn u32(&mut self, v: u32) {
        self.put(&v.to_le_bytes());
    }

    pub(crate) fn u64(&mut self, v: u64) {
        self.put(&v.to_le_bytes());
    }

    /// Stores `v` as the record's `float` (rounded to nearest).
    #[allow(clippy::cast_possible_truncation)]
    pub(crate) fn f32(&mut self, v: f64) {
        self.put(&(v as f32).to_le_bytes());
    }

    pub(crate) fn f64(&mut self, v: f64) {
        self.put(&v.to_le_bytes());
    }

    pub(crate) fn f32s(&mut self, v: &[f64]) {
        for &x in v {
            self.f32(x);
        }
    }

    pub(crate) fn f64s(&mut self, v: &[f64]) {
        for &x in v {
            self.f64(x);
        }
    }

    pub(crate) fn bools(&mut self, v: &[bool]) {
        for &x in v {
            self.bool(x);
        }
    }

    pub(crate) fn position(&self) -> usize {
        self.at
    }
}
