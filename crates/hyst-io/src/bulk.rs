//! Delimited records read fast: blocks of whole lines parsed in parallel.
//!
//! A record as instruments and scripts write it — no quotes, one row a line ending in LF or
//! CRLF — is read here in blocks of [`BLOCK_BYTES`], each split at line ends into pieces
//! parsed on every core, each piece's lines counted first so that it writes its rows
//! straight into its own stretch of the columns, while the next block is read into a second
//! buffer: the memory besides the numbers is two blocks, as bounded as the `csv` crate's
//! stream. Cells are read by Clinger's fast path where it is exact, else by `str::parse`
//! (the same double to the bit either way). On `cargo xtask bench command`'s 115 MB record
//! (10⁶ rows of ten cells) this takes 0.25–0.29 s on two cores, pandas' C reader 0.28 s in
//! the same run. Anything else (a quote, a lone
//! CR, a cell that is not a number, a row with another count of cells, a line past
//! [`MAX_LINE_BYTES`](super::delimited::MAX_LINE_BYTES)) gives `None`, and the caller reads
//! the file with the `csv` crate, which says what is wrong where, as before: the fast path
//! reads exactly what that reader reads, or leaves the file to it.

use std::io::Read;
use std::path::Path;

use rayon::prelude::*;

use super::NonFiniteCell;
use super::delimited::{MAX_LINE_BYTES, number};

/// Bytes read at a time (then cut back to the last line end).
const BLOCK_BYTES: usize = 2 << 20;

/// Pieces per block and core: enough that a piece's rows take a few milliseconds.
const PIECES_PER_THREAD: usize = 4;

/// The columns of a record: each column's values and its first cell that is not finite.
pub(super) struct Columns {
    pub(super) values: Vec<Vec<f64>>,
    pub(super) non_finite: Vec<Option<NonFiniteCell>>,
}

/// One piece's rows parsed: how many it wrote (its blank lines wrote none), and each
/// column's first cell that is not finite (a line within the piece, 0-based, and its value).
struct Piece {
    rows: usize,
    non_finite: Vec<Option<(usize, f64)>>,
}

/// The data rows of `path` (`columns` cells each, split at `sep`), from the line after its
/// header (or from its first line when `headerless`), when every one of them is a plain
/// row; `None` otherwise, and when the file cannot be read (the `csv` reader then says
/// why).
pub(super) fn read(path: &Path, columns: usize, sep: u8, headerless: bool) -> Option<Columns> {
    read_blocks(path, columns, sep, headerless, BLOCK_BYTES)
}

/// [`read`] in blocks of `block` bytes.
fn read_blocks(
    path: &Path,
    columns: usize,
    sep: u8,
    headerless: bool,
    block: usize,
) -> Option<Columns> {
    let mut file = std::fs::File::open(path).ok()?;
    let mut out = Columns {
        values: vec![Vec::new(); columns],
        non_finite: vec![None; columns],
    };
    let size = file.metadata().map_or(0, |m| m.len() as usize);
    // Two buffers: while the pieces of one block are parsed, the next is read into the
    // other (the read is a fifth of the time on one core). Each holds a block and what was
    // left of the last one's final line.
    let mut buf: Vec<u8> = Vec::new();
    let mut next: Vec<u8> = Vec::new();
    let (mut have, mut eof) = fill(&mut file, &mut buf, 0, block)?;
    // Lines before the block's first (1-based numbering: the next row's line is `line + 1`).
    let mut line = 0usize;
    let mut start = data_start(&buf[..have], headerless, &mut line)?;
    // Room for the rows the file holds if its lines are as long as its first block's: the
    // columns then seldom grow (each growth copies them).
    let lines_here = memchr::memchr_iter(b'\n', &buf[start..have]).count().max(1);
    let rows = (size as f64 / have.max(1) as f64 * lines_here as f64 * 1.02) as usize;
    out.values.iter_mut().for_each(|v| v.reserve(rows + 1));
    loop {
        // Whole lines only, but all of what is left at the end of the file.
        let end = if eof {
            have
        } else {
            match memchr::memrchr(b'\n', &buf[start..have]) {
                Some(p) => start + p + 1,
                None if have - start > MAX_LINE_BYTES => return None,
                None => {
                    buf.copy_within(start..have, 0);
                    (have, eof) = fill(&mut file, &mut buf, have - start, block)?;
                    start = 0;
                    continue;
                }
            }
        };
        let tail = have - end;
        if next.len() < tail + block {
            next.resize(tail + block, 0);
        }
        next[..tail].copy_from_slice(&buf[end..have]);
        let (parsed, read) = rayon::join(
            || parse_block(&buf[start..end], columns, sep, line, &mut out),
            || {
                if eof {
                    Some((tail, true))
                } else {
                    fill(&mut file, &mut next, tail, block)
                }
            },
        );
        line += parsed?;
        if eof && tail == 0 {
            break;
        }
        (have, eof) = read?;
        std::mem::swap(&mut buf, &mut next);
        start = 0;
    }
    Some(out)
}

/// `buf` holding `have` bytes, with up to `block` more read from `file` after them (the
/// buffer grown as needed): the bytes it then holds, and whether the file ended.
fn fill(
    file: &mut std::fs::File,
    buf: &mut Vec<u8>,
    mut have: usize,
    block: usize,
) -> Option<(usize, bool)> {
    let want = have + block;
    if buf.len() < want {
        buf.resize(want, 0);
    }
    while have < want {
        match file.read(&mut buf[have..want]) {
            Ok(0) => return Some((have, true)),
            Ok(n) => have += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => return None,
        }
    }
    Some((have, false))
}

/// Where the data rows of a file whose first block is `buf` begin: after a byte-order mark,
/// blank lines and the header line (unless `headerless`), counting the lines passed into
/// `line`. `None` if the header line holds a quote (a quoted name may span lines) or is not
/// in the block.
fn data_start(buf: &[u8], headerless: bool, line: &mut usize) -> Option<usize> {
    let mut at = if buf.starts_with(b"\xEF\xBB\xBF") {
        3
    } else {
        0
    };
    loop {
        let len = buf[at..].iter().position(|&b| b == b'\n')?;
        let text = &buf[at..at + len];
        if text.contains(&b'"') {
            return None;
        }
        if text.iter().all(u8::is_ascii_whitespace) {
            at += len + 1;
            *line += 1;
            continue;
        }
        if headerless {
            return Some(at);
        }
        *line += 1;
        return Some(at + len + 1);
    }
}

/// Parse the whole lines `block`, whose first is line `line + 1` of the file, in pieces on
/// every core, appending their rows to `out`; the block's lines, or `None` if a line is not
/// a plain row. Each piece's lines are counted first, and it writes its rows straight into
/// its own stretch of every column (no piece's columns are copied after).
fn parse_block(
    block: &[u8],
    columns: usize,
    sep: u8,
    line: usize,
    out: &mut Columns,
) -> Option<usize> {
    let pieces = rayon::current_num_threads() * PIECES_PER_THREAD;
    let mut cuts = vec![0];
    for k in 1..pieces {
        let guess = block.len() * k / pieces;
        let last = *cuts.last().unwrap_or(&0);
        if guess <= last {
            continue;
        }
        match memchr::memchr(b'\n', &block[guess..]) {
            Some(p) if guess + p + 1 < block.len() => cuts.push(guess + p + 1),
            _ => break,
        }
    }
    cuts.push(block.len());
    let texts: Vec<&[u8]> = cuts.windows(2).map(|w| &block[w[0]..w[1]]).collect();
    // A piece's lines: its line ends, and one more if the last lacks its end.
    let lines: Vec<usize> = texts
        .par_iter()
        .map(|t| {
            memchr::memchr_iter(b'\n', t).count()
                + usize::from(!t.is_empty() && !t.ends_with(b"\n"))
        })
        .collect();
    let total: usize = lines.iter().sum();
    let base = out.values.first().map_or(0, Vec::len);
    for v in &mut out.values {
        v.resize(base + total, 0.0);
    }
    // Every column's new stretch cut into the pieces' parts.
    let mut parts: Vec<Vec<&mut [f64]>> = (0..texts.len()).map(|_| Vec::new()).collect();
    for v in &mut out.values {
        let mut rest = &mut v[base..];
        for (k, &n) in lines.iter().enumerate() {
            let (mine, tail) = rest.split_at_mut(n);
            parts[k].push(mine);
            rest = tail;
        }
    }
    let parsed: Vec<Option<Piece>> = texts
        .par_iter()
        .zip(parts.into_par_iter())
        .map(|(t, mut cols)| parse_piece(t, &mut cols, sep))
        .collect();
    // Rows written, each piece's moved down over the slots of blank lines before it.
    let mut rows = base;
    let mut slot = base;
    let mut seen = 0;
    for (k, piece) in parsed.into_iter().enumerate() {
        let piece = piece?;
        for c in 0..columns {
            if out.non_finite[c].is_none()
                && let Some((at, value)) = piece.non_finite[c]
            {
                out.non_finite[c] = Some(NonFiniteCell {
                    row: line + seen + at + 1,
                    value,
                });
            }
            if rows != slot {
                out.values[c].copy_within(slot..slot + piece.rows, rows);
            }
        }
        rows += piece.rows;
        slot += lines[k];
        seen += lines[k];
    }
    for v in &mut out.values {
        v.truncate(rows);
    }
    Some(total)
}

/// The rows of the whole lines `piece` (the last may lack its line end) written into
/// `cols` (one slot per line), or `None` if one is not a plain row of as many numbers as
/// there are columns, split at `sep`.
fn parse_piece(piece: &[u8], cols: &mut [&mut [f64]], sep: u8) -> Option<Piece> {
    let columns = cols.len();
    let mut out = Piece {
        rows: 0,
        non_finite: vec![None; columns],
    };
    // A quote is the `csv` reader's to read (quoted cells).
    if memchr::memchr(b'"', piece).is_some() {
        return None;
    }
    let body = piece.strip_suffix(b"\n").unwrap_or(piece);
    if piece.is_empty() {
        return Some(out);
    }
    let mut from = 0;
    let ends = memchr::memchr_iter(b'\n', body).chain(std::iter::once(body.len()));
    for (at, to) in ends.enumerate() {
        let raw = &body[from..to];
        from = to + 1;
        let text = raw.strip_suffix(b"\r").unwrap_or(raw);
        // A lone CR (old Mac line ends) is the `csv` reader's to read; so is a line too
        // long for it.
        if text.len() > MAX_LINE_BYTES || memchr::memchr(b'\r', text).is_some() {
            return None;
        }
        // A blank line is skipped, as the `csv` reader's caller skips it: one without the
        // delimiter (a lone empty cell), or of spaces when they are the delimiter.
        if text.iter().all(u8::is_ascii_whitespace) && (sep == b' ' || !text.contains(&sep)) {
            continue;
        }
        let row = out.rows;
        let mut count = 0;
        let mut cell = |bytes: &[u8]| -> Option<()> {
            if count == columns {
                return None;
            }
            let v = match plain_decimal(bytes) {
                Some(v) => v,
                None => number(std::str::from_utf8(bytes).ok()?.trim(), sep)?,
            };
            if !v.is_finite() && out.non_finite[count].is_none() {
                out.non_finite[count] = Some((at, v));
            }
            cols[count][row] = v;
            count += 1;
            Some(())
        };
        if sep == b' ' {
            for c in text.split(|&b| b == b' ').filter(|c| !c.is_empty()) {
                cell(c)?;
            }
        } else {
            let mut from = 0;
            for to in memchr::memchr_iter(sep, text) {
                cell(&text[from..to])?;
                from = to + 1;
            }
            cell(&text[from..])?;
        }
        if count != columns {
            return None;
        }
        out.rows += 1;
    }
    Some(out)
}

/// 10⁰ … 10²², every one an exact double.
const POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// A plain decimal cell (`-1.5`, `2e-3`, ` 4.25E+01 `: a sign, digits with at most one
/// point, an exponent; spaces or tabs around it) read exactly as `str::parse` reads it, when
/// its significant digits make an integer below 2⁵³ and its power of ten lies within
/// 10^±22: both are then exact doubles and one multiplication or division rounds correctly
/// (Clinger's fast path, the first step of every correct reader of decimals). `None` for
/// anything else, which `str::parse` is left to read or refuse.
fn plain_decimal(b: &[u8]) -> Option<f64> {
    let blank = |c: u8| c == b' ' || c == b'\t';
    let mut i = 0;
    let mut end = b.len();
    while i < end && blank(b[i]) {
        i += 1;
    }
    while end > i && blank(b[end - 1]) {
        end -= 1;
    }
    let negative = match b.get(i) {
        Some(b'-') => {
            i += 1;
            true
        }
        Some(b'+') => {
            i += 1;
            false
        }
        _ => false,
    };
    let (mut mantissa, mut digits, mut power, mut any) = (0u64, 0u32, 0i32, false);
    // The digits before the point, then after it (each lowering the power by one); leading
    // zeros are no significant digits.
    let mut digit = |d: u8, after_point: bool| -> Option<()> {
        any = true;
        power -= i32::from(after_point);
        if mantissa != 0 || d != 0 {
            if digits == 19 {
                return None;
            }
            mantissa = mantissa * 10 + u64::from(d);
            digits += 1;
        }
        Some(())
    };
    while i < end && b[i].is_ascii_digit() {
        digit(b[i] - b'0', false)?;
        i += 1;
    }
    if i < end && b[i] == b'.' {
        i += 1;
        while i < end && b[i].is_ascii_digit() {
            digit(b[i] - b'0', true)?;
            i += 1;
        }
    }
    if !any {
        return None;
    }
    if i < end && (b[i] | 0x20) == b'e' {
        i += 1;
        let sign = match b.get(i) {
            Some(b'-') => {
                i += 1;
                -1
            }
            Some(b'+') => {
                i += 1;
                1
            }
            _ => 1,
        };
        let (mut e, mut e_digits) = (0i32, 0);
        while i < end && b[i].is_ascii_digit() {
            if e_digits == 4 {
                return None;
            }
            e = e * 10 + i32::from(b[i] - b'0');
            e_digits += 1;
            i += 1;
        }
        if e_digits == 0 {
            return None;
        }
        power += sign * e;
    }
    if i != end || mantissa > 1 << 53 {
        return None;
    }
    let m = mantissa as f64;
    let v = if mantissa == 0 {
        0.0
    } else if (0..=22).contains(&power) {
        m * POWERS_OF_TEN[power as usize]
    } else if (-22..0).contains(&power) {
        m / POWERS_OF_TEN[(-power) as usize]
    } else {
        return None;
    };
    Some(if negative { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The file `text` read by the `csv` reader and by the blocks of `block` bytes: equal
    /// wherever the fast path reads it.
    fn both(text: &str, block: usize) -> Result<(), TestCaseError> {
        let path = crate::test_files::file_path("bulk-property.csv");
        std::fs::write(&path, text).expect("written");
        let rows = crate::delimited::DelimitedRows::open_record(&path, Default::default());
        let Ok(rows) = rows else { return Ok(()) };
        let (n, sep, headerless) = (rows.names.len(), rows.sep, rows.pending.is_some());
        let slow = crate::delimited::streamed(&path, rows);
        if let Some(fast) = read_blocks(&path, n, sep, headerless, block) {
            let (values, non_finite) = slow.map_err(|e| {
                TestCaseError::fail(format!("fast read what the csv reader refuses: {e}"))
            })?;
            let bits = |v: &Vec<Vec<f64>>| -> Vec<Vec<u64>> {
                v.iter()
                    .map(|c| c.iter().map(|x| x.to_bits()).collect())
                    .collect()
            };
            prop_assert_eq!(bits(&fast.values), bits(&values));
            let rows_of = |v: &[Option<NonFiniteCell>]| -> Vec<Option<usize>> {
                v.iter().map(|c| c.map(|c| c.row)).collect()
            };
            prop_assert_eq!(rows_of(&fast.non_finite), rows_of(&non_finite));
        }
        Ok(())
    }

    /// A line of a record: numbers (some not finite, some with spaces), sometimes too few
    /// or too many, a blank line, a quoted cell, a lone CR.
    fn line() -> impl Strategy<Value = String> {
        let cell = prop_oneof![
            60 => (-1e6f64..1e6).prop_map(|v| format!("{v}")),
            20 => (-1e3f64..1e3).prop_map(|v| format!("{v:.6e}")),
            1 => Just(" 2.5 ".to_string()),
            1 => Just("NaN".to_string()),
            1 => Just("inf".to_string()),
            1 => Just("\"3\"".to_string()),
            1 => Just("x".to_string()),
            1 => Just(String::new()),
        ];
        prop_oneof![
            40 => proptest::collection::vec(cell.clone(), 3).prop_map(|c| c.join(",")),
            1 => proptest::collection::vec(cell, 2..5).prop_map(|c| c.join(",")),
            1 => Just(String::new()),
            1 => Just("   ".to_string()),
            1 => Just("1,2\r3".to_string()),
        ]
    }

    /// A cell as instruments and people write numbers, and near misses.
    fn decimal_text() -> impl Strategy<Value = String> {
        let digits = "[0-9]{0,22}";
        (
            prop_oneof![Just(""), Just("-"), Just("+"), Just(" ")],
            digits,
            prop_oneof![Just(""), Just("."), Just(".."), Just(",")],
            digits,
            prop_oneof![Just(""), Just("e"), Just("E-"), Just("e+"), Just("e0")],
            "[0-9]{0,5}",
            prop_oneof![Just(""), Just(" "), Just("\t"), Just("x")],
        )
            .prop_map(|(s, a, p, b, e, x, t)| format!("{s}{a}{p}{b}{e}{x}{t}"))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(5000))]
        /// The fast reader of decimals reads what `str::parse` reads, to the bit, or leaves
        /// the cell to it.
        #[test]
        fn plain_decimals_read_as_the_standard_reader_reads_them(text in decimal_text()) {
            if let Some(v) = plain_decimal(text.as_bytes()) {
                let std: f64 = text.trim().parse().map_err(|_| {
                    TestCaseError::fail(format!("{text:?} read as {v}, refused by str::parse"))
                })?;
                prop_assert_eq!(v.to_bits(), std.to_bits(), "{:?}", text);
            }
        }

        /// Every double printed as `{:e}` and `{}` (shortest round trip) reads back as
        /// itself, by the fast reader where it takes it.
        #[test]
        fn printed_doubles_read_back(v in any::<f64>().prop_filter("finite", |v| v.is_finite())) {
            for text in [format!("{v:e}"), format!("{v}"), format!("{v:.6e}")] {
                if let Some(r) = plain_decimal(text.as_bytes()) {
                    let std: f64 = text.parse().expect("a double's text");
                    prop_assert_eq!(r.to_bits(), std.to_bits(), "{:?}", text);
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// Wherever the fast path reads a file, it reads what the `csv` reader reads: the
        /// same numbers to the bit, the same first non-finite cell of each column; and it
        /// reads no file that reader refuses.
        #[test]
        fn the_fast_path_reads_what_the_csv_reader_reads(
            header in prop_oneof![Just("a,b,c"), Just("\u{feff}a, b ,c"), Just("\n a,b,c")],
            lines in proptest::collection::vec(line(), 0..40),
            crlf in any::<bool>(),
            last_end in any::<bool>(),
            block in 8usize..200,
        ) {
            let end = if crlf { "\r\n" } else { "\n" };
            let mut text = format!("{header}{end}{}", lines.join(end));
            if last_end {
                text.push_str(end);
            }
            both(&text, block)?;
        }
    }

    #[test]
    fn what_the_fast_reader_of_decimals_takes_and_leaves() {
        for (text, v) in [
            ("-1.234567e-03", -1.234567e-3f64),
            (" 42 ", 42.0),
            ("0.000125", 0.000125),
            ("-0.0", -0.0),
            ("5.", 5.0),
            (".5", 0.5),
            ("1E+22", 1e22),
        ] {
            assert_eq!(
                plain_decimal(text.as_bytes()).map(f64::to_bits),
                Some(v.to_bits()),
                "{text}"
            );
        }
        // Left to `str::parse`: words, a decimal comma, digits beyond 2⁵³, powers beyond 10²².
        for text in [
            "NaN",
            "inf",
            "1,5",
            "12345678901234567890",
            "1e23",
            "1e-23",
            "e5",
            ".",
        ] {
            assert_eq!(plain_decimal(text.as_bytes()), None, "{text}");
        }
    }

    #[test]
    fn a_plain_record_is_read_by_the_fast_path_across_blocks() {
        let path = crate::test_files::file_path("bulk-plain.csv");
        let mut text = String::from("t,y\r\n\r\n");
        for k in 0..1000 {
            text.push_str(&format!("{},{:.6e}\r\n", k, (k as f64 * 0.1).sin()));
        }
        std::fs::write(&path, &text).expect("written");
        let c = read_blocks(&path, 2, b',', false, 97).expect("a plain record");
        assert_eq!(c.values[0].len(), 1000);
        assert_eq!(c.values[0][999], 999.0);
        assert_eq!(
            c.values[1][10],
            format!("{:.6e}", 1.0f64.sin()).parse::<f64>().unwrap()
        );
        let table = crate::delimited::read_csv(&path).expect("read");
        assert_eq!(table.names, ["t", "y"]);
    }
}
