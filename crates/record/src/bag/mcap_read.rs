//! A careful MCAP reader: every length is checked against the bytes that
//! hold it before anything is reserved or sliced, chunks are decompressed
//! with their declared size as a bound and checked against their CRC, and
//! every fault names its byte offset.
//!
//! The `mcap` crate's `MessageStream` reads chunks without a record-length
//! limit (its chunk flattener sets none, and a record length of 2⁶⁴−1
//! panicked inside it) and checks no chunk CRC unless asked, and then cannot
//! say which chunk failed or what it held. Its records are simple, so they
//! are read here (MCAP format: <https://mcap.dev/spec>); the crate still
//! writes the bags.

use std::collections::HashMap;

/// The magic at both ends of an MCAP file.
const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";
/// Opcode and length of a record.
const RECORD_HEAD: usize = 9;

mod op {
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const MESSAGE_INDEX: u8 = 0x07;
    pub const DATA_END: u8 = 0x0F;
}

/// A channel: its topic, message encoding and schema name (`None`: no
/// schema).
#[derive(Clone, Debug)]
pub(super) struct Channel {
    pub topic: String,
    pub encoding: String,
    pub schema: Option<String>,
}

/// One message as read: its channel, log time and bytes.
#[derive(Debug)]
pub(super) struct Raw {
    pub channel: u16,
    pub log_time_ns: u64,
    pub data: Vec<u8>,
}

/// A chunk that could not be read: where, why, and what it held (from the
/// message indexes after it, when they are readable).
#[derive(Debug)]
pub(super) struct BadChunk {
    /// Byte offset of the chunk record.
    pub offset: usize,
    /// What is wrong.
    pub why: String,
    /// `(channel, messages)` from its message indexes.
    pub held: Vec<(u16, usize)>,
}

/// The messages of a file, its channels, and the chunks that could not be
/// read (only when `keep_going`).
#[derive(Debug, Default)]
pub(super) struct Contents {
    pub messages: Vec<Raw>,
    pub channels: HashMap<u16, Channel>,
    pub bad_chunks: Vec<BadChunk>,
    /// The data section's CRC did not match, though every chunk did (damage
    /// in a record outside the chunks: a message index, a chunk's header).
    pub data_crc_mismatch: Option<String>,
}

/// A little-endian cursor over a record's body; every read is bounded.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    what: &'static str,
}

impl<'a> Body<'a> {
    fn new(bytes: &'a [u8], what: &'static str) -> Self {
        Self { bytes, at: 0, what }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| {
                format!(
                    "{} record of {} bytes: a field of {n} bytes at byte {} runs past its end",
                    self.what,
                    self.bytes.len(),
                    self.at
                )
            })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    fn u16(&mut self) -> Result<u16, String> {
        self.array().map(u16::from_le_bytes)
    }

    fn u32(&mut self) -> Result<u32, String> {
        self.array().map(u32::from_le_bytes)
    }

    fn u64(&mut self) -> Result<u64, String> {
        self.array().map(u64::from_le_bytes)
    }

    /// A length-prefixed block: its `u32` (or `u64`) length is checked
    /// against the bytes left before it is taken.
    fn block32(&mut self) -> Result<&'a [u8], String> {
        let n = self.u32()?;
        self.take(usize::try_from(n).unwrap_or(usize::MAX))
    }

    fn string(&mut self) -> Result<String, String> {
        let what = self.what;
        let b = self.block32()?;
        String::from_utf8(b.to_vec()).map_err(|_| format!("{what} record: a string not UTF-8"))
    }

    fn rest(&mut self) -> &'a [u8] {
        let s = &self.bytes[self.at..];
        self.at = self.bytes.len();
        s
    }
}

/// The records of `bytes` from `start`: `(offset, opcode, body)`, each
/// length checked against the bytes left. Ends at the end of `bytes` or
/// after a footer record.
fn records(
    bytes: &[u8],
    start: usize,
    base: usize,
) -> impl Iterator<Item = Result<(usize, u8, &[u8]), String>> {
    let mut at = start;
    let mut done = false;
    std::iter::from_fn(move || {
        if done || at >= bytes.len() {
            return None;
        }
        let offset = base + at;
        let left = bytes.len() - at;
        if left < RECORD_HEAD {
            done = true;
            return Some(Err(format!(
                "offset {offset}: {left} bytes, too few for a record (cut short?)"
            )));
        }
        let opcode = bytes[at];
        let mut len = [0; 8];
        len.copy_from_slice(&bytes[at + 1..at + RECORD_HEAD]);
        let len = u64::from_le_bytes(len);
        let room = left - RECORD_HEAD;
        if len > room as u64 {
            done = true;
            return Some(Err(format!(
                "offset {offset}: a record (opcode 0x{opcode:02x}) of {len} bytes, but only {room} follow (damaged or cut short)"
            )));
        }
        let body = &bytes[at + RECORD_HEAD..at + RECORD_HEAD + len as usize];
        at += RECORD_HEAD + len as usize;
        if opcode == op::FOOTER {
            done = true;
        }
        Some(Ok((offset, opcode, body)))
    })
}

/// The records of one chunk, decompressed, or what is wrong with it.
fn chunk_records(body: &[u8], max_uncompressed: u64) -> Result<Vec<u8>, String> {
    let mut b = Body::new(body, "chunk");
    let _start = b.u64()?;
    let _end = b.u64()?;
    let size = b.u64()?;
    let crc = b.u32()?;
    let compression = b.string()?;
    let compressed_size = b.u64()?;
    let data = b.take(usize::try_from(compressed_size).unwrap_or(usize::MAX))?;
    if size > max_uncompressed {
        return Err(format!(
            "declares {size} bytes uncompressed, more than the {max_uncompressed} a bag may hold"
        ));
    }
    let out = match compression.as_str() {
        "" => data.to_vec(),
        "zstd" => {
            use std::io::Read;
            let mut out = Vec::new();
            zstd::stream::read::Decoder::new(data)
                .map_err(|e| format!("zstd: {e}"))?
                .take(size.saturating_add(1))
                .read_to_end(&mut out)
                .map_err(|e| format!("its zstd data does not decompress: {e}"))?;
            out
        }
        other => {
            return Err(format!(
                "compressed with `{other}`, which surveyor does not read (zstd or none)"
            ));
        }
    };
    if out.len() as u64 != size {
        return Err(format!(
            "{} bytes uncompressed, but it declares {size}",
            out.len()
        ));
    }
    if crc != 0 {
        let found = crc32fast::hash(&out);
        if found != crc {
            return Err(format!(
                "CRC 0x{found:08x} of its data, but it declares 0x{crc:08x}"
            ));
        }
    }
    Ok(out)
}

/// What one record adds: a schema, a channel or a message.
fn read_record(
    opcode: u8,
    body: &[u8],
    schemas: &mut HashMap<u16, String>,
    channels: &mut HashMap<u16, Channel>,
    messages: &mut Vec<Raw>,
) -> Result<(), String> {
    match opcode {
        op::SCHEMA => {
            let mut b = Body::new(body, "schema");
            let id = b.u16()?;
            let name = b.string()?;
            let _encoding = b.string()?;
            b.block32()?;
            if id == 0 {
                return Err("a schema with ID 0 (reserved for none)".into());
            }
            match schemas.get(&id) {
                Some(old) if *old != name => {
                    return Err(format!("schema {id} is `{old}`, and again `{name}`"));
                }
                _ => {
                    schemas.insert(id, name);
                }
            }
        }
        op::CHANNEL => {
            let mut b = Body::new(body, "channel");
            let id = b.u16()?;
            let schema_id = b.u16()?;
            let topic = b.string()?;
            let encoding = b.string()?;
            b.block32()?;
            let schema =
                match schema_id {
                    0 => None,
                    s => Some(schemas.get(&s).cloned().ok_or_else(|| {
                        format!("channel {topic} names schema {s}, not yet read")
                    })?),
                };
            let channel = Channel {
                topic,
                encoding,
                schema,
            };
            if let Some(old) = channels.get(&id) {
                if old.topic != channel.topic || old.schema != channel.schema {
                    return Err(format!(
                        "channel {id} is {} and again {}",
                        old.topic, channel.topic
                    ));
                }
            } else {
                channels.insert(id, channel);
            }
        }
        op::MESSAGE => {
            let mut b = Body::new(body, "message");
            let channel = b.u16()?;
            let sequence = b.u32()?;
            let log_time_ns = b.u64()?;
            let _publish = b.u64()?;
            if !channels.contains_key(&channel) {
                return Err(format!(
                    "message {sequence} on channel {channel}, which no channel record defines"
                ));
            }
            messages.push(Raw {
                channel,
                log_time_ns,
                data: b.rest().to_vec(),
            });
        }
        _ => {}
    }
    Ok(())
}

/// `(channel, messages)` of a message index record.
fn message_index(body: &[u8]) -> Result<(u16, usize), String> {
    let mut b = Body::new(body, "message index");
    let channel = b.u16()?;
    let entries = b.block32()?;
    Ok((channel, entries.len() / 16))
}

/// Every message of the MCAP file `bytes` (of at most `max_uncompressed`
/// bytes in any chunk). A damaged chunk is an error naming its offset,
/// unless `keep_going`: it is then listed in [`Contents::bad_chunks`] and
/// read on. A broken record outside the chunks is always an error: what
/// follows it cannot be found.
pub(super) fn read(
    bytes: &[u8],
    keep_going: bool,
    max_uncompressed: u64,
) -> Result<Contents, String> {
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != *MAGIC {
        return Err("not an MCAP file (no magic at its start)".into());
    }
    let all: Vec<(usize, u8, &[u8])> = records(bytes, MAGIC.len(), 0).collect::<Result<_, _>>()?;
    let data_end = all
        .iter()
        .position(|(_, opcode, _)| *opcode == op::DATA_END)
        .unwrap_or(all.len());
    let mut out = Contents::default();
    let mut schemas = HashMap::new();
    // The summary's schemas and channels first: a damaged chunk may have
    // defined a channel that later chunks use, and they name what it held.
    for (_, opcode, body) in &all[data_end..] {
        if *opcode == op::SCHEMA || *opcode == op::CHANNEL {
            let mut ignored = Vec::new();
            let (mut s, mut c) = (schemas.clone(), out.channels.clone());
            if read_record(*opcode, body, &mut s, &mut c, &mut ignored).is_ok() {
                (schemas, out.channels) = (s, c);
            }
        }
    }
    let mut bad: Option<BadChunk> = None;
    let mut footer_end = None;
    for &(offset, opcode, body) in &all {
        if opcode != op::MESSAGE_INDEX
            && let Some(b) = bad.take()
        {
            out.bad_chunks.push(b);
        }
        if opcode == op::FOOTER {
            footer_end = Some(offset + RECORD_HEAD + body.len());
        }
        if footer_end.is_some() || offset > all.get(data_end).map_or(usize::MAX, |r| r.0) {
            continue;
        }
        match opcode {
            op::CHUNK => {
                let read = chunk_records(body, max_uncompressed).and_then(|inner| {
                    let mut messages = Vec::new();
                    let mut channels = out.channels.clone();
                    let mut inner_schemas = schemas.clone();
                    for r in records(&inner, 0, 0) {
                        let (at, opcode, body) =
                            r.map_err(|e| format!("inside, at its byte {e}"))?;
                        read_record(
                            opcode,
                            body,
                            &mut inner_schemas,
                            &mut channels,
                            &mut messages,
                        )
                        .map_err(|e| format!("inside, at its byte {at}: {e}"))?;
                    }
                    Ok((messages, channels, inner_schemas))
                });
                match read {
                    Ok((messages, channels, inner_schemas)) => {
                        out.messages.extend(messages);
                        out.channels = channels;
                        schemas = inner_schemas;
                    }
                    Err(why) => {
                        bad = Some(BadChunk {
                            offset,
                            why,
                            held: Vec::new(),
                        });
                    }
                }
            }
            op::MESSAGE_INDEX => {
                if let Some(b) = &mut bad
                    && let Ok(held) = message_index(body)
                {
                    b.held.push(held);
                }
            }
            op::DATA_END => {
                let mut b = Body::new(body, "data end");
                let saved = b.u32().map_err(|e| format!("offset {offset}: {e}"))?;
                let found = crc32fast::hash(&bytes[..offset]);
                if saved != 0 && saved != found {
                    out.data_crc_mismatch = Some(format!(
                        "the data section's CRC is 0x{found:08x}, but its end record (offset {offset}) declares 0x{saved:08x}"
                    ));
                }
            }
            _ => {
                read_record(
                    opcode,
                    body,
                    &mut schemas,
                    &mut out.channels,
                    &mut out.messages,
                )
                .map_err(|e| format!("offset {offset}: {e}"))?;
            }
        }
    }
    if let Some(b) = bad.take() {
        out.bad_chunks.push(b);
    }
    let Some(end) = footer_end else {
        return Err("no footer record: the file is cut short".into());
    };
    if bytes.get(end..) != Some(MAGIC.as_slice()) {
        return Err(format!(
            "offset {end}: not the end magic after the footer (the file is damaged or cut short)"
        ));
    }
    if !keep_going {
        if let Some(b) = out.bad_chunks.first() {
            return Err(describe(b, &out.channels));
        }
        if let Some(e) = &out.data_crc_mismatch {
            return Err(e.clone());
        }
    }
    Ok(out)
}

/// A damaged chunk in words: its offset, what is wrong, what it held.
pub(super) fn describe(b: &BadChunk, channels: &HashMap<u16, Channel>) -> String {
    let held = if b.held.is_empty() {
        "messages its index does not say".to_owned()
    } else {
        b.held
            .iter()
            .map(|(c, n)| {
                let topic = channels
                    .get(c)
                    .map_or_else(|| format!("channel {c}"), |c| c.topic.clone());
                format!("{n} on {topic}")
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "the chunk at offset {} is damaged ({}); it held {held}",
        b.offset, b.why
    )
}

/// Messages a damaged chunk held, when its index says.
pub(super) fn lost(b: &BadChunk) -> Option<usize> {
    (!b.held.is_empty()).then(|| b.held.iter().map(|(_, n)| n).sum())
}
