//! MCAP files of ROS 2 messages: [`BagWriter`] writes CDR-encoded messages
//! with their `ros2msg` schemas (the layout `ros2 bag record -s mcap`
//! writes), [`read_bag`] reads any such file back, message by message.

use super::BagError;
use super::msg::RosMessage;
use serde::de::DeserializeOwned;
use std::collections::{BTreeMap, HashMap};
use std::io::{Seek, Write};
use std::path::Path;

/// The CDR encapsulation header ROS 2 puts before every message:
/// plain CDR, little-endian.
const CDR_LE: [u8; 4] = [0, 1, 0, 0];
/// The header of a big-endian message.
const CDR_BE: [u8; 4] = [0, 0, 0, 0];

/// CDR bytes of `msg` (little-endian, with the encapsulation header).
pub fn encode<M: RosMessage>(msg: &M) -> Result<Vec<u8>, BagError> {
    let mut out = CDR_LE.to_vec();
    cdr_encoding::to_writer::<_, byteorder::LittleEndian, _>(&mut out, msg).map_err(|e| {
        BagError::Encode {
            type_name: M::TYPE,
            message: e.to_string(),
        }
    })?;
    Ok(out)
}

/// The message of type `M` in the CDR bytes `data` (either byte order).
pub fn decode<M: RosMessage + DeserializeOwned>(data: &[u8]) -> Result<M, BagError> {
    let bad = |message: String| BagError::Decode {
        type_name: M::TYPE,
        message,
    };
    let (header, body) = data
        .split_at_checked(4)
        .ok_or_else(|| bad(format!("{} bytes, shorter than the CDR header", data.len())))?;
    let decoded = if header == CDR_LE {
        cdr_encoding::from_bytes::<M, byteorder::LittleEndian>(body)
    } else if header == CDR_BE {
        cdr_encoding::from_bytes::<M, byteorder::BigEndian>(body)
    } else {
        return Err(bad(format!(
            "encapsulation {header:02x?}, expected plain CDR (00 01 00 00 or 00 00 00 00)"
        )));
    };
    decoded.map(|(m, _)| m).map_err(|e| bad(e.to_string()))
}

/// Writes ROS 2 messages into an MCAP file (profile `ros2`, schemas
/// `ros2msg`, messages `cdr`, zstd-compressed chunks). Each topic's channel
/// is added with its first message.
pub struct BagWriter<W: Write + Seek> {
    mcap: mcap::Writer<W>,
    schemas: HashMap<&'static str, u16>,
    channels: HashMap<String, (u16, &'static str)>,
    sequence: u32,
}

impl<W: Write + Seek> std::fmt::Debug for BagWriter<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagWriter")
            .field("channels", &self.channels)
            .field("messages", &self.sequence)
            .finish_non_exhaustive()
    }
}

impl<W: Write + Seek> BagWriter<W> {
    /// A bag written into `w`.
    pub fn new(w: W) -> Result<Self, BagError> {
        Self::with_chunk_size(w, None)
    }

    /// A bag written into `w` in chunks of about `chunk_bytes` each
    /// (uncompressed; `None`: the `mcap` crate's default).
    pub fn with_chunk_size(w: W, chunk_bytes: Option<u64>) -> Result<Self, BagError> {
        let mut options = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("surveyor ", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd));
        if chunk_bytes.is_some() {
            options = options.chunk_size(chunk_bytes);
        }
        let mcap = options.create(w)?;
        Ok(Self {
            mcap,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            sequence: 0,
        })
    }

    /// Messages written so far.
    pub fn messages(&self) -> u32 {
        self.sequence
    }

    /// Write `msg` on `topic`, logged at `stamp_ns`. A topic carries one type.
    pub fn write<M: RosMessage>(
        &mut self,
        topic: &str,
        stamp_ns: u64,
        msg: &M,
    ) -> Result<(), BagError> {
        let channel_id = self.channel::<M>(topic)?;
        let data = encode(msg)?;
        self.sequence += 1;
        self.mcap.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: stamp_ns,
                publish_time: stamp_ns,
            },
            &data,
        )?;
        Ok(())
    }

    /// The channel of `topic`, added on first use.
    fn channel<M: RosMessage>(&mut self, topic: &str) -> Result<u16, BagError> {
        if let Some(&(id, type_name)) = self.channels.get(topic) {
            if type_name != M::TYPE {
                return Err(BagError::TopicType {
                    topic: topic.to_owned(),
                    has: type_name,
                    given: M::TYPE,
                });
            }
            return Ok(id);
        }
        let schema = if let Some(&id) = self.schemas.get(M::TYPE) {
            id
        } else {
            let id = self
                .mcap
                .add_schema(M::TYPE, "ros2msg", M::definition().as_bytes())?;
            self.schemas.insert(M::TYPE, id);
            id
        };
        let id = self
            .mcap
            .add_channel(schema, topic, "cdr", &BTreeMap::new())?;
        self.channels.insert(topic.to_owned(), (id, M::TYPE));
        Ok(id)
    }

    /// Write the summary and footer; the finished output.
    pub fn finish(mut self) -> Result<W, BagError> {
        self.mcap.finish()?;
        Ok(self.mcap.into_inner())
    }
}

/// One message of a bag, still encoded.
#[derive(Clone, Debug, PartialEq)]
pub struct BagMessage {
    /// Its topic.
    pub topic: String,
    /// Its type (`package/msg/Type`, the channel's schema name).
    pub type_name: String,
    /// Its place among its topic's messages in the file, from 0.
    pub index: usize,
    /// When it was logged, nanoseconds.
    pub log_time_ns: u64,
    /// CDR bytes.
    pub data: Vec<u8>,
}

impl BagMessage {
    /// Decode as `M`, which must be the message's type.
    pub fn decode<M: RosMessage + DeserializeOwned>(&self) -> Result<M, BagError> {
        if self.type_name != M::TYPE {
            return Err(BagError::Decode {
                type_name: M::TYPE,
                message: format!("topic {} carries {}", self.topic, self.type_name),
            });
        }
        decode(&self.data)
    }

    /// The message in words: `/scan message 12 (logged at 3.250000000 s)`.
    pub fn name(&self) -> String {
        format!(
            "{} message {} (logged at {}.{:09} s)",
            self.topic,
            self.index,
            self.log_time_ns / 1_000_000_000,
            self.log_time_ns % 1_000_000_000
        )
    }
}

/// What reading a bag does with a damaged chunk or a bad message.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BadMessages {
    /// Refuse the bag, naming the chunk or the message (the default: a
    /// damaged bag never maps silently).
    #[default]
    Refuse,
    /// Skip it and count it (`--skip-bad-messages`).
    Skip,
}

/// What was skipped reading a bag with [`BadMessages::Skip`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Skipped {
    /// Messages lost: those of damaged chunks (as their indexes count them)
    /// and bad messages.
    pub messages: usize,
    /// Each damaged chunk and bad message in words.
    pub what: Vec<String>,
}

impl Skipped {
    /// Count `n` messages lost to `what`.
    pub fn add(&mut self, n: usize, what: String) {
        self.messages += n;
        self.what.push(what);
    }
}

/// The messages of a bag and what was skipped reading it.
#[derive(Clone, Debug, Default)]
pub struct BagContents {
    /// The messages, in the file's order.
    pub messages: Vec<BagMessage>,
    /// Damaged chunks skipped ([`BadMessages::Skip`] only).
    pub skipped: Skipped,
}

/// Largest bag [`read_bag`] reads, bytes (it holds the whole file in memory);
/// also the most one chunk may declare uncompressed.
pub const MAX_BAG_BYTES: u64 = 8 << 30;

/// Every message of the MCAP file at `path` whose topic `wanted` accepts, in
/// the file's order; a damaged chunk refuses the bag, naming its offset and
/// the topics it held. Messages must carry CDR with a schema.
pub fn read_bag(path: &Path, wanted: &dyn Fn(&str) -> bool) -> Result<Vec<BagMessage>, BagError> {
    read_bag_with(path, wanted, BadMessages::Refuse).map(|c| c.messages)
}

/// [`read_bag`], with damaged chunks refused or skipped as `bad` says.
/// Every length in the file is checked against the bytes that hold it
/// before anything is reserved; every chunk is checked against its CRC.
pub fn read_bag_with(
    path: &Path,
    wanted: &dyn Fn(&str) -> bool,
    bad_messages: BadMessages,
) -> Result<BagContents, BagError> {
    let io = |e: std::io::Error| BagError::Io {
        path: path.to_owned(),
        source: e,
    };
    let size = std::fs::metadata(path).map_err(io)?.len();
    if size > MAX_BAG_BYTES {
        return Err(BagError::TooLarge {
            path: path.to_owned(),
            bytes: size,
        });
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let bad = |message: String| BagError::Bag {
        path: path.to_owned(),
        message,
    };
    let contents = super::mcap_read::read(&bytes, bad_messages == BadMessages::Skip, MAX_BAG_BYTES)
        .map_err(&bad)?;
    let mut skipped = Skipped::default();
    for b in &contents.bad_chunks {
        let what = super::mcap_read::describe(b, &contents.channels);
        match super::mcap_read::lost(b) {
            Some(n) => skipped.add(n, what),
            None => {
                skipped.what.push(what);
            }
        }
    }
    if let Some(e) = contents.data_crc_mismatch {
        skipped.what.push(e);
    }
    let mut out = Vec::new();
    let mut counts: HashMap<u16, usize> = HashMap::new();
    for m in contents.messages {
        let count = counts.entry(m.channel).or_default();
        let index = *count;
        *count += 1;
        let Some(channel) = contents.channels.get(&m.channel) else {
            continue;
        };
        if !wanted(&channel.topic) {
            continue;
        }
        if channel.encoding != "cdr" {
            return Err(bad(format!(
                "topic {} is encoded as `{}`, expected ROS 2 `cdr`",
                channel.topic, channel.encoding
            )));
        }
        let type_name = channel
            .schema
            .clone()
            .ok_or_else(|| bad(format!("topic {} has no schema", channel.topic)))?;
        out.push(BagMessage {
            topic: channel.topic.clone(),
            type_name,
            index,
            log_time_ns: m.log_time_ns,
            data: m.data,
        });
    }
    Ok(BagContents {
        messages: out,
        skipped,
    })
}
