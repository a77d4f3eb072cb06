//! The `.npy` header: the magic, the version, the header's length and the dict literal
//! `{'descr': …, 'fortran_order': …, 'shape': (…), }` (NumPy's `numpy.lib.format`).

use std::io::Read;

/// The first six bytes of every `.npy` file.
const MAGIC: &[u8] = b"\x93NUMPY";

/// The header is padded so that the magic, version, length and header take a multiple of
/// this many bytes (NumPy's `ARRAY_ALIGN`).
const ALIGN: usize = 64;

/// The longest header read: NumPy's own reader refuses headers over 10 000 bytes by default.
const MAX_HEADER_LEN: usize = 100_000;

/// The three keys of an `.npy` header.
#[derive(Debug, PartialEq)]
pub(super) struct Header {
    /// The dtype, as NumPy spells it (`<f8` is little-endian float64).
    pub descr: String,
    /// Whether the values are stored in Fortran (column-major) order.
    pub fortran_order: bool,
    /// The array's shape.
    pub shape: Vec<usize>,
}

/// A header that cannot be read: the file failed or ended, or the header is malformed.
#[derive(Debug)]
pub(super) enum HeaderError {
    /// Reading failed, or the file ended inside the header.
    Io(std::io::Error),
    /// The bytes are not an `.npy` header: the message says why.
    Invalid(String),
}

impl From<std::io::Error> for HeaderError {
    fn from(err: std::io::Error) -> Self {
        HeaderError::Io(err)
    }
}

/// The version 1.0 header of a C-order array of `descr` and `shape`: the dict (with no comma
/// before its closing brace, as `vesicle` has always written it), spaces, and a newline, to a
/// multiple of 64 bytes (a whole 64 more when the dict and newline already end on one, as
/// NumPy pads).
pub(super) fn to_bytes(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape = match dims.as_slice() {
        [one] => format!("({one},)"),
        _ => format!("({})", dims.join(", ")),
    };
    let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}}}");
    let prefix = MAGIC.len() + 2 + 2;
    let unpadded = prefix + dict.len() + 1;
    let total = unpadded + ALIGN - unpadded % ALIGN;
    let header_len = u16::try_from(total - prefix).expect("a header of 2 or 3 axes fits u16");
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    out
}

impl Header {
    /// Read the magic, version (1.0, 2.0 or 3.0), length and dict of a header from `reader`,
    /// leaving it at the first value.
    pub fn from_reader(reader: &mut impl Read) -> Result<Self, HeaderError> {
        let mut start = [0u8; 8];
        reader.read_exact(&mut start)?;
        if &start[..6] != MAGIC {
            return Err(invalid(
                "the file does not start with the npy magic \\x93NUMPY",
            ));
        }
        let len = match (start[6], start[7]) {
            (1, 0) => {
                let mut len = [0u8; 2];
                reader.read_exact(&mut len)?;
                usize::from(u16::from_le_bytes(len))
            }
            (2 | 3, 0) => {
                let mut len = [0u8; 4];
                reader.read_exact(&mut len)?;
                usize::try_from(u32::from_le_bytes(len)).unwrap_or(usize::MAX)
            }
            (major, minor) => {
                return Err(invalid(format!("unknown format version {major}.{minor}")))
            }
        };
        if len > MAX_HEADER_LEN {
            return Err(invalid(format!(
                "the header is {len} bytes long (at most {MAX_HEADER_LEN} are read)"
            )));
        }
        let mut text = vec![0u8; len];
        reader.read_exact(&mut text)?;
        let text = std::str::from_utf8(&text).map_err(|_| invalid("the header is not text"))?;
        Self::parse(text)
    }

    /// Parse the dict literal, with its keys in any order; trailing whitespace (the padding
    /// and newline) is allowed.
    fn parse(text: &str) -> Result<Self, HeaderError> {
        let mut p = Parser { rest: text };
        let (mut descr, mut fortran_order, mut shape) = (None, None, None);
        p.expect('{')?;
        while !p.eat('}') {
            let key = p.string()?;
            p.expect(':')?;
            match key {
                "descr" => descr = Some(p.string()?.to_string()),
                "fortran_order" => fortran_order = Some(p.boolean()?),
                "shape" => shape = Some(p.tuple()?),
                other => return Err(invalid(format!("unknown key '{other}'"))),
            }
            if !p.eat(',') {
                p.expect('}')?;
                break;
            }
        }
        if !p.rest.trim().is_empty() {
            return Err(invalid(format!(
                "unexpected {:?} after the dict",
                p.rest.trim()
            )));
        }
        let missing = |key: &str| invalid(format!("missing key '{key}'"));
        Ok(Header {
            descr: descr.ok_or_else(|| missing("descr"))?,
            fortran_order: fortran_order.ok_or_else(|| missing("fortran_order"))?,
            shape: shape.ok_or_else(|| missing("shape"))?,
        })
    }
}

/// A malformed header.
fn invalid(message: impl Into<String>) -> HeaderError {
    HeaderError::Invalid(message.into())
}

/// The unread rest of a header's dict literal; every token may be preceded by whitespace.
struct Parser<'a> {
    rest: &'a str,
}

impl<'a> Parser<'a> {
    /// Consume `c` if it comes next.
    fn eat(&mut self, c: char) -> bool {
        self.rest = self.rest.trim_start();
        match self.rest.strip_prefix(c) {
            Some(rest) => {
                self.rest = rest;
                true
            }
            None => false,
        }
    }

    /// Consume `c`, which must come next.
    fn expect(&mut self, c: char) -> Result<(), HeaderError> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(self.unexpected(&format!("'{c}'")))
        }
    }

    /// A string in single or double quotes, without escapes.
    fn string(&mut self) -> Result<&'a str, HeaderError> {
        for quote in ['\'', '"'] {
            if self.eat(quote) {
                let end = self
                    .rest
                    .find(quote)
                    .ok_or_else(|| invalid("unterminated string"))?;
                let (s, rest) = self.rest.split_at(end);
                if s.contains('\\') {
                    return Err(invalid(format!("escapes in the string {s:?}")));
                }
                self.rest = &rest[1..];
                return Ok(s);
            }
        }
        Err(self.unexpected("a string"))
    }

    /// `True` or `False`.
    fn boolean(&mut self) -> Result<bool, HeaderError> {
        self.rest = self.rest.trim_start();
        for (word, value) in [("True", true), ("False", false)] {
            if let Some(rest) = self.rest.strip_prefix(word) {
                self.rest = rest;
                return Ok(value);
            }
        }
        Err(self.unexpected("True or False"))
    }

    /// A tuple of non-negative integers: `()`, `(n,)` or `(n0, n1, …)`, a trailing comma
    /// allowed.
    fn tuple(&mut self) -> Result<Vec<usize>, HeaderError> {
        self.expect('(')?;
        let mut items = Vec::new();
        while !self.eat(')') {
            items.push(self.integer()?);
            if !self.eat(',') {
                self.expect(')')?;
                break;
            }
        }
        Ok(items)
    }

    /// A non-negative integer that fits `usize`.
    fn integer(&mut self) -> Result<usize, HeaderError> {
        self.rest = self.rest.trim_start();
        let end = self
            .rest
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(self.rest.len());
        if end == 0 {
            return Err(self.unexpected("a non-negative integer"));
        }
        let (digits, rest) = self.rest.split_at(end);
        let n = digits
            .parse()
            .map_err(|_| invalid(format!("the dimension {digits} is too large")))?;
        self.rest = rest;
        Ok(n)
    }

    /// An error saying what was expected and what comes instead.
    fn unexpected(&self, what: &str) -> HeaderError {
        let found: String = self.rest.chars().take(20).collect();
        invalid(format!("expected {what}, found {found:?}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header of a 96 × 96 field as `vesicle` wrote it through ndarray-npy 0.10.
    const WRITTEN_96X96: &[u8] = b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': \
        False, 'shape': (96, 96)}                                                          \n";

    #[test]
    fn written_header_is_unchanged() {
        assert_eq!(WRITTEN_96X96.len(), 128);
        assert_eq!(to_bytes("<f8", &[96, 96]), WRITTEN_96X96);
    }

    #[test]
    fn written_header_ends_on_64_bytes_and_reads_back() {
        for shape in [
            vec![3],
            vec![5, 7],
            vec![128, 128, 128],
            vec![usize::MAX; 3],
        ] {
            let bytes = to_bytes("<f8", &shape);
            assert_eq!(bytes.len() % ALIGN, 0, "{shape:?}");
            let header = Header::from_reader(&mut bytes.as_slice()).unwrap();
            let want = Header {
                descr: "<f8".into(),
                fortran_order: false,
                shape,
            };
            assert_eq!(header, want);
        }
    }

    /// A dict that ends on 64 bytes with its newline gets a whole 64 bytes of padding more,
    /// as NumPy's `_wrap_header` gives it.
    #[test]
    fn aligned_dict_gets_64_more_bytes() {
        // Digits 3 × 20: 10 bytes of prefix, 117 of dict and the newline make 128.
        let shape = [10usize.pow(19); 3];
        let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape:?}}}");
        assert_eq!(10 + dict.len() + 1, 128);
        assert_eq!(to_bytes("<f8", &shape).len(), 192);
    }

    #[test]
    fn keys_in_any_order_with_other_spacing_and_quotes() {
        let text = "{ \"shape\" : ( 4 , 5 ) ,'fortran_order':True,'descr':'>f8'}  \n";
        let header = Header::parse(text).unwrap();
        assert_eq!(header.shape, [4, 5]);
        assert!(header.fortran_order);
        assert_eq!(header.descr, ">f8");
        assert_eq!(
            Header::parse("{'descr': '<f8', 'fortran_order': False, 'shape': ()}\n")
                .unwrap()
                .shape,
            Vec::<usize>::new()
        );
    }

    #[test]
    fn malformed_headers_say_what_is_wrong() {
        for (text, words) in [
            (
                "{'descr': '<f8', 'fortran_order': False}",
                "missing key 'shape'",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), 'x': 1}",
                "unknown key 'x'",
            ),
            (
                "{'descr': '<f8', 'fortran_order': 0, 'shape': (2,)}",
                "True or False",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (-2,)}",
                "non-negative",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999999,)}",
                "too large",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (2,)} x",
                "after the dict",
            ),
            ("{'descr: '<f8'}", "expected ':'"),
            ("[1, 2]", "expected '{'"),
        ] {
            match Header::parse(text) {
                Err(HeaderError::Invalid(m)) => assert!(m.contains(words), "{text}: {m}"),
                other => panic!("{text}: {other:?}"),
            }
        }
    }

    #[test]
    fn versions_2_and_3_have_a_4_byte_length() {
        let dict = b"{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n";
        for version in [2u8, 3] {
            let mut bytes = b"\x93NUMPY".to_vec();
            bytes.extend([version, 0]);
            bytes.extend((dict.len() as u32).to_le_bytes());
            bytes.extend(dict);
            let header = Header::from_reader(&mut bytes.as_slice()).unwrap();
            assert_eq!(header.shape, [2, 3]);
        }
        let mut bytes = b"\x93NUMPY\x04\x00".to_vec();
        bytes.extend([0u8; 4]);
        match Header::from_reader(&mut bytes.as_slice()) {
            Err(HeaderError::Invalid(m)) => assert!(m.contains("version 4.0"), "{m}"),
            other => panic!("{other:?}"),
        }
    }
}
