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
        let mcap = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("surveyor ", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd))
            .create(w)?;
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
}

/// Largest bag [`read_bag`] reads, bytes (it holds the whole file in memory).
pub const MAX_BAG_BYTES: u64 = 8 << 30;

/// Every message of the MCAP file at `path` whose topic `wanted` accepts, in
/// the file's order. Messages must carry CDR with a schema.
pub fn read_bag(path: &Path, wanted: &dyn Fn(&str) -> bool) -> Result<Vec<BagMessage>, BagError> {
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
    let mut out = Vec::new();
    for (k, message) in mcap::MessageStream::new(&bytes)
        .map_err(|e| bad(e.to_string()))?
        .enumerate()
    {
        let message = message.map_err(|e| bad(format!("message {k}: {e}")))?;
        let channel = &message.channel;
        if !wanted(&channel.topic) {
            continue;
        }
        if channel.message_encoding != "cdr" {
            return Err(bad(format!(
                "topic {} is encoded as `{}`, expected ROS 2 `cdr`",
                channel.topic, channel.message_encoding
            )));
        }
        let type_name = channel
            .schema
            .as_ref()
            .map(|s| s.name.clone())
            .ok_or_else(|| bad(format!("topic {} has no schema", channel.topic)))?;
        out.push(BagMessage {
            topic: channel.topic.clone(),
            type_name,
            log_time_ns: message.log_time,
            data: message.data.into_owned(),
        });
    }
    Ok(out)
}
