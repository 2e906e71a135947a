//! Reading the messages of an MCAP file held in memory without trusting the lengths it states.
//!
//! mcap's `MessageStream` reads with no bound on a record's length: a record or a chunk's
//! record that claims petabytes makes it allocate them (the process aborts) or overflow an
//! addition (it panics) before it finds the bytes are not there. A record of an uncompressed
//! chunk that runs past the chunk's end makes it subtract past zero (a panic with overflow
//! checks, reading on with garbage without), and it parses every record, attachments too, whose
//! parser slices past the end of one too short for its CRC (a panic). Found by the `demo_mcap`
//! and `ros2_bag` fuzz targets (`fuzz/`). [`messages`] first checks every uncompressed chunk's
//! records end where the chunk does, then reads through mcap's sans-io reader with every
//! record, chunk and decompressed chunk bounded by [`record_limit`], and parses only the
//! schemas, channels and messages it needs: any such file is an error like any other damage.

use std::borrow::Cow;

use mcap::read::ChannelAccumulator;
use mcap::records::{op, Record};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::{McapError, McapResult, Message};

/// How many times its file's size a record may hold once decompressed: chunks of recorded
/// poses and joint states compress a few times, nowhere near this.
const MAX_EXPANSION: usize = 64;

/// The bound for files smaller than `MIN_LIMIT / MAX_EXPANSION` (256 KiB), whose one chunk
/// could compress unusually well (mcap's writer closes a chunk at 768 KiB).
const MIN_LIMIT: usize = 16 << 20;

/// The most bytes one record of a `len`-byte MCAP file may hold, decompressed.
fn record_limit(len: usize) -> usize {
    len.saturating_mul(MAX_EXPANSION).max(MIN_LIMIT)
}

/// The messages of the MCAP file `bytes` in file order, each linked to its channel; a record
/// longer than [`record_limit`] is an error. With `to_data_end` the stream ends at the data
/// end record and a missing end magic is no error (a recording cut short). An uncompressed
/// chunk whose records run past its end is refused before any message is read.
pub(crate) fn messages(bytes: &[u8], to_data_end: bool) -> Result<Messages<'_>, McapError> {
    check_chunk_records(bytes)?;
    let options = LinearReaderOptions::default()
        .with_record_length_limit(record_limit(bytes.len()))
        .with_skip_end_magic(to_data_end);
    Ok(Messages {
        unread: bytes,
        reader: LinearReader::new_with_options(options),
        channels: ChannelAccumulator::default(),
        to_data_end,
        past_data_end: false,
        done: false,
    })
}

/// The messages of an MCAP file (see [`messages`]), as mcap's `MessageStream` yields them,
/// nothing after the first error.
pub(crate) struct Messages<'a> {
    /// What the reader has not been given yet.
    unread: &'a [u8],
    reader: LinearReader,
    channels: ChannelAccumulator<'static>,
    /// End at the data end record.
    to_data_end: bool,
    /// The data end record has been read: what follows is the summary, skipped.
    past_data_end: bool,
    done: bool,
}

impl Iterator for Messages<'_> {
    type Item = McapResult<Message<'static>>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let item = self.next_message();
        if !matches!(item, Some(Ok(_))) {
            self.done = true;
        }
        item
    }
}

impl Messages<'_> {
    fn next_message(&mut self) -> Option<McapResult<Message<'static>>> {
        while let Some(event) = self.reader.next_event() {
            let (opcode, data) = match event {
                Err(e) => return Some(Err(e)),
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let given = need.min(self.unread.len());
                    let (now, later) = self.unread.split_at(given);
                    self.reader.insert(given).copy_from_slice(now);
                    self.reader.notify_read(given);
                    self.unread = later;
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => (opcode, data),
            };
            match opcode {
                op::DATA_END if self.to_data_end => return None,
                op::DATA_END => self.past_data_end = true,
                _ if self.past_data_end => {}
                op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                    let record = match mcap::parse_record(opcode, data) {
                        Ok(record) => record,
                        Err(e) => return Some(Err(e)),
                    };
                    let added = match record {
                        Record::Schema { header, data } => self
                            .channels
                            .add_schema(header, Cow::Owned(data.into_owned())),
                        Record::Channel(channel) => self.channels.add_channel(channel),
                        Record::Message { header, data } => {
                            return Some(match self.channels.get(header.channel_id) {
                                Some(channel) => Ok(Message {
                                    channel,
                                    sequence: header.sequence,
                                    log_time: header.log_time,
                                    publish_time: header.publish_time,
                                    data: Cow::Owned(data.into_owned()),
                                }),
                                None => Err(McapError::UnknownChannel(
                                    header.sequence,
                                    header.channel_id,
                                )),
                            })
                        }
                        _ => Ok(()),
                    };
                    if let Err(e) = added {
                        return Some(Err(e));
                    }
                }
                // Attachments, metadata, indexes, statistics: never parsed.
                _ => {}
            }
        }
        None
    }
}

/// Checks that no record of an uncompressed chunk runs past the chunk's records (compressed
/// chunks mcap checks as it decompresses them). Walks the file's records as mcap's reader does,
/// as far as the file holds them: a chunk is read record by record from its header on, so a
/// chunk cut short by the end of the file is checked as far as it goes. Anything else wrong is
/// left to the message stream, which reports it where it meets it.
fn check_chunk_records(bytes: &[u8]) -> Result<(), McapError> {
    let mut rest = bytes.get(MAGIC_LENGTH..).unwrap_or_default();
    while let Some((&opcode, after)) = rest.split_first() {
        let Some((length, body)) = after.split_first_chunk::<8>() else {
            break;
        };
        let length = usize::try_from(u64::from_le_bytes(*length)).unwrap_or(usize::MAX);
        if opcode == CHUNK_OPCODE {
            check_chunk(&body[..length.min(body.len())])?;
        }
        match body.get(length..) {
            Some(next) => rest = next,
            None => break,
        }
    }
    Ok(())
}

/// The MCAP magic's length: the first record follows it.
const MAGIC_LENGTH: usize = 8;

/// The opcode of a chunk record.
const CHUNK_OPCODE: u8 = 0x06;

/// Checks one chunk record's body, as much of it as the file holds: its start and end times,
/// uncompressed size and CRC (28 bytes), the compression's name (a u32 length and the name),
/// the records' size (u64) and the records.
fn check_chunk(body: &[u8]) -> Result<(), McapError> {
    let Some((name_length, after)) = body.get(28..).and_then(<[u8]>::split_first_chunk::<4>) else {
        return Ok(());
    };
    if u32::from_le_bytes(*name_length) != 0 {
        return Ok(());
    }
    match after.split_first_chunk::<8>() {
        Some((size, records)) => records_fit(records, u64::from_le_bytes(*size)),
        None => Ok(()),
    }
}

/// Whether the records of a chunk whose records take `size` bytes (each an opcode, a
/// little-endian u64 length and that many bytes) stay within them, as far as `records` (the
/// bytes the file holds from the first on) shows.
fn records_fit(mut records: &[u8], mut size: u64) -> Result<(), McapError> {
    while size > 0 {
        let Some((length, rest)) = records.get(1..).and_then(<[u8]>::split_first_chunk::<8>) else {
            return Ok(());
        };
        let length = u64::from_le_bytes(*length);
        let whole = length
            .checked_add(9)
            .filter(|&whole| whole <= size)
            .ok_or(McapError::UnexpectedEoc)?;
        size -= whole;
        match usize::try_from(length).ok().and_then(|l| rest.get(l..)) {
            Some(next) => records = next,
            None => return Ok(()),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The MCAP magic and one record whose length is the largest a u64 holds: mcap's
    /// `MessageStream` panicked on it (the `demo_mcap` fuzz target's first find).
    const ENDLESS_RECORD: &[u8] = b"\x89MCAP0\r\n\x01\xff\xff\xff\xff\xff\xff\xff\xff";

    #[test]
    fn a_record_longer_than_the_bound_is_an_error() {
        let first = messages(ENDLESS_RECORD, true).unwrap().next();
        assert!(
            matches!(first, Some(Err(mcap::McapError::RecordTooLarge { .. }))),
            "{first:?}"
        );
    }

    /// A file whose one chunk is zstd-compressed and holds the start of a record claiming
    /// 2^62 bytes: mcap's `MessageStream` asked the allocator for them and the process aborted
    /// (the `demo_mcap` and `ros2_bag` fuzz targets' second find).
    fn chunk_with_a_huge_record() -> Vec<u8> {
        let mut inner = vec![0x05]; // a message record's opcode, then its length
        inner.extend_from_slice(&(1u64 << 62).to_le_bytes());
        // A zstd frame of one raw block: magic, a single-segment descriptor with a one-byte
        // content size, the block header (last block, raw, its size) and the bytes.
        let mut zstd = vec![0x28, 0xb5, 0x2f, 0xfd, 0x20, inner.len() as u8];
        let block = 1 | (inner.len() as u32) << 3;
        zstd.extend_from_slice(&block.to_le_bytes()[..3]);
        zstd.extend_from_slice(&inner);
        let mut chunk = Vec::new();
        chunk.extend_from_slice(&0u64.to_le_bytes()); // first message time
        chunk.extend_from_slice(&0u64.to_le_bytes()); // last message time
        chunk.extend_from_slice(&(inner.len() as u64).to_le_bytes());
        chunk.extend_from_slice(&0u32.to_le_bytes()); // no CRC
        chunk.extend_from_slice(&4u32.to_le_bytes());
        chunk.extend_from_slice(b"zstd");
        chunk.extend_from_slice(&(zstd.len() as u64).to_le_bytes());
        chunk.extend_from_slice(&zstd);
        let mut file = b"\x89MCAP0\r\n".to_vec();
        file.push(0x06); // the chunk record's opcode, then its length
        file.extend_from_slice(&(chunk.len() as u64).to_le_bytes());
        file.extend_from_slice(&chunk);
        file
    }

    #[test]
    fn a_compressed_record_longer_than_the_bound_is_an_error() {
        let file = chunk_with_a_huge_record();
        let first = messages(&file, true).unwrap().next();
        assert!(
            matches!(first, Some(Err(mcap::McapError::RecordTooLarge { .. }))),
            "{first:?}"
        );
    }

    /// A file whose one uncompressed chunk holds a record claiming 1 KiB in 9 bytes: mcap's
    /// reader subtracted the length from what was left of the chunk and overflowed (the
    /// `demo_mcap` fuzz target's third find).
    fn chunk_with_a_record_past_its_end() -> Vec<u8> {
        let mut records = vec![0x05]; // a message record's opcode, then its length
        records.extend_from_slice(&1024u64.to_le_bytes());
        let mut chunk = Vec::new();
        chunk.extend_from_slice(&[0; 16]); // first and last message times
        chunk.extend_from_slice(&(records.len() as u64).to_le_bytes());
        chunk.extend_from_slice(&0u32.to_le_bytes()); // no CRC
        chunk.extend_from_slice(&0u32.to_le_bytes()); // no compression
        chunk.extend_from_slice(&(records.len() as u64).to_le_bytes());
        chunk.extend_from_slice(&records);
        let mut file = b"\x89MCAP0\r\n".to_vec();
        file.push(0x06); // the chunk record's opcode, then its length
        file.extend_from_slice(&(chunk.len() as u64).to_le_bytes());
        file.extend_from_slice(&chunk);
        // Another record after the chunk, which the reader took for the rest of the record.
        file.extend_from_slice(&[0x0f; 1100]);
        file
    }

    #[test]
    fn an_uncompressed_chunk_whose_record_runs_past_its_end_is_refused() {
        let mut file = chunk_with_a_record_past_its_end();
        assert!(matches!(
            messages(&file, true),
            Err(McapError::UnexpectedEoc)
        ));
        // The same chunk claiming more bytes than the file holds: mcap reads a chunk record by
        // record from its header on, so it overflowed all the same (the fuzz targets' fourth).
        file[9..17].copy_from_slice(&(1u64 << 40).to_le_bytes());
        assert!(matches!(
            messages(&file, true),
            Err(McapError::UnexpectedEoc)
        ));
    }

    #[test]
    fn records_fit_only_when_each_stays_within_the_chunk() {
        let record = |length: u64, body: usize| {
            let mut r = vec![0x05];
            r.extend_from_slice(&length.to_le_bytes());
            r.extend(std::iter::repeat_n(0u8, body));
            r
        };
        let two = [record(3, 3), record(0, 0)].concat();
        assert!(records_fit(&[], 0).is_ok());
        assert!(records_fit(&two, 21).is_ok());
        assert!(records_fit(&two, 20).is_err());
        assert!(records_fit(&record(4, 3), 12).is_err());
        assert!(records_fit(&record(u64::MAX, 3), 12).is_err());
        // A chunk the file cuts short is checked as far as it goes.
        assert!(records_fit(&record(3, 3)[..5], 12).is_ok());
        assert!(records_fit(&two[..14], 21).is_ok());
    }

    #[test]
    fn an_attachment_too_short_for_its_crc_is_never_parsed() {
        // Log and create times, an empty name and media type, a data length and no room for
        // the CRC: mcap's attachment parser sliced past the end (the fuzz targets' fifth).
        let body = [0u8; 32];
        let mut file = b"\x89MCAP0\r\n".to_vec();
        file.push(0x09); // an attachment record's opcode, then its length
        file.extend_from_slice(&(body.len() as u64).to_le_bytes());
        file.extend_from_slice(&body);
        let read: Vec<_> = messages(&file, true).unwrap().collect();
        assert!(read.iter().all(Result::is_err), "{read:?}");
        assert!(read.len() <= 1);
    }

    #[test]
    fn the_bound_grows_with_the_file_from_a_floor() {
        assert_eq!(record_limit(0), MIN_LIMIT);
        assert_eq!(record_limit(1 << 30), 64 << 30);
        assert_eq!(record_limit(usize::MAX), usize::MAX);
    }
}
