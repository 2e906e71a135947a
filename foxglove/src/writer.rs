//! An MCAP writer of JSON messages on channels typed by their message.

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::marker::PhantomData;

use crate::schema::Message;

/// Nanoseconds of `t` seconds, rounded; negative times are 0 (an MCAP log time).
pub(crate) fn nanos(t: f64) -> u64 {
    (t.max(0.0) * 1e9).round() as u64
}

/// Why a message or a file could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// The MCAP writer failed (most often: the output failed).
    #[error(transparent)]
    Mcap(#[from] mcap::McapError),
    /// A message could not be written as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

/// A channel of messages of type `M` in one [`McapWriter`].
pub struct Channel<M> {
    id: u16,
    message: PhantomData<fn(&M)>,
}

impl<M> Clone for Channel<M> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M> Copy for Channel<M> {}

impl<M: Message> Channel<M> {
    /// `message` at `t` seconds, encoded for this channel, to be written later (e.g. after
    /// sorting messages of several channels by time).
    pub fn encode(self, t: f64, message: &M) -> Result<Encoded, WriteError> {
        Ok(Encoded {
            t,
            channel: self.id,
            data: serde_json::to_vec(message)?,
        })
    }
}

/// A message encoded for its channel, not yet written.
#[derive(Debug, Clone, PartialEq)]
pub struct Encoded {
    /// Its time (seconds): its log and publish time.
    pub t: f64,
    channel: u16,
    data: Vec<u8>,
}

/// An MCAP file being written: each schema once, channels typed by their message, messages
/// numbered in the order written.
pub struct McapWriter<W: Write + Seek> {
    writer: mcap::Writer<W>,
    schemas: BTreeMap<&'static str, u16>,
    sequence: u32,
}

impl<W: Write + Seek> McapWriter<W> {
    /// Starts a file on `out` with the given options (profile, chunking).
    pub fn new(out: W, options: mcap::WriteOptions) -> Result<Self, WriteError> {
        Ok(McapWriter {
            writer: options.create(out)?,
            schemas: BTreeMap::new(),
            sequence: 0,
        })
    }

    /// Adds a channel on `topic` for messages of type `M` (JSON-encoded, with `M`'s JSON schema,
    /// written once however many channels use it).
    pub fn channel<M: Message>(&mut self, topic: &str) -> Result<Channel<M>, WriteError> {
        let schema = match self.schemas.get(M::NAME) {
            Some(&id) => id,
            None => {
                let text = M::titled_schema().to_string();
                let id = self
                    .writer
                    .add_schema(M::NAME, "jsonschema", text.as_bytes())?;
                self.schemas.insert(M::NAME, id);
                id
            }
        };
        let id = self
            .writer
            .add_channel(schema, topic, "json", &BTreeMap::new())?;
        Ok(Channel {
            id,
            message: PhantomData,
        })
    }

    /// Writes `message` at `t` seconds on `channel`.
    pub fn write<M: Message>(
        &mut self,
        channel: Channel<M>,
        t: f64,
        message: &M,
    ) -> Result<(), WriteError> {
        self.write_encoded(&channel.encode(t, message)?)
    }

    /// Writes a message encoded before.
    pub fn write_encoded(&mut self, message: &Encoded) -> Result<(), WriteError> {
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id: message.channel,
            sequence: self.sequence,
            log_time: nanos(message.t),
            publish_time: nanos(message.t),
        };
        self.writer.write_to_known_channel(&header, &message.data)?;
        Ok(())
    }

    /// Writes a metadata record `name`.
    pub fn metadata(
        &mut self,
        name: &str,
        metadata: BTreeMap<String, String>,
    ) -> Result<(), WriteError> {
        self.writer.write_metadata(&mcap::records::Metadata {
            name: name.into(),
            metadata,
        })?;
        Ok(())
    }

    /// Closes the current chunk, so that what was written survives a crash.
    pub fn flush(&mut self) -> Result<(), WriteError> {
        self.writer.flush()?;
        Ok(())
    }

    /// Writes the summary and returns the output.
    pub fn finish(mut self) -> Result<W, WriteError> {
        self.writer.finish()?;
        Ok(self.writer.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{Log, LogLevel, Time};
    use std::io::Cursor;

    #[test]
    fn times_round_to_the_nanosecond_and_start_at_zero() {
        assert_eq!(nanos(1.5), 1_500_000_000);
        assert_eq!(nanos(-2.0), 0);
        assert_eq!(Time::at(3.000_000_000_4), Time { sec: 3, nsec: 0 });
        assert_eq!(
            Time::at(2.25),
            Time {
                sec: 2,
                nsec: 250_000_000
            }
        );
    }

    #[test]
    fn a_schema_is_written_once_and_messages_read_back_on_their_channels() {
        let mut w = McapWriter::new(Cursor::new(Vec::new()), mcap::WriteOptions::new()).unwrap();
        let a = w.channel::<Log>("/a").unwrap();
        let b = w.channel::<Log>("/b").unwrap();
        w.write(
            b,
            1.5,
            &Log::new(1.5, LogLevel::Error, "akl.test", "late".into()),
        )
        .unwrap();
        w.write(
            a,
            0.5,
            &Log::new(0.5, LogLevel::Info, "akl.test", "early".into()),
        )
        .unwrap();
        let bytes = w.finish().unwrap().into_inner();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        assert_eq!(summary.schemas.len(), 1);
        let read: Vec<(String, u64, u32, serde_json::Value)> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| {
                let m = m.unwrap();
                let value = serde_json::from_slice(&m.data).unwrap();
                (m.channel.topic.clone(), m.log_time, m.sequence, value)
            })
            .collect();
        assert_eq!(read[0].0, "/b");
        assert_eq!((read[0].1, read[0].2), (1_500_000_000, 1));
        assert_eq!(read[0].3["level"], 4);
        assert_eq!(read[0].3["timestamp"]["nsec"], 500_000_000);
        assert_eq!(read[1].0, "/a");
        assert_eq!(read[1].3["message"], "early");
        assert_eq!(read[1].3["level"], 2);
    }
}
