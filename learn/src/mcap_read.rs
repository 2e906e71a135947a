//! Reading the messages of an MCAP file held in memory without trusting the lengths it states.
//!
//! mcap's `MessageStream` reads with no bound on a record's length: a record or a chunk's
//! record that claims petabytes makes it allocate them (the process aborts) or overflow an
//! addition (it panics) before it finds the bytes are not there. Found by the `demo_mcap` and
//! `ros2_bag` fuzz targets (`fuzz/`). [`messages`] reads through mcap's streaming reader with
//! every record, chunk and decompressed chunk bounded by [`record_limit`], so such a file is
//! an error like any other damage.

use std::io::Cursor;

use mcap::io::MessageReader;
use mcap::sans_io::LinearReaderOptions;

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
/// end record and a missing end magic is no error (a recording cut short).
pub(crate) fn messages(bytes: &[u8], to_data_end: bool) -> MessageReader<Cursor<&[u8]>> {
    let options = LinearReaderOptions::default()
        .with_record_length_limit(record_limit(bytes.len()))
        .with_skip_end_magic(to_data_end);
    MessageReader::new_with_options(Cursor::new(bytes), options)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The MCAP magic and one record whose length is the largest a u64 holds: mcap's
    /// `MessageStream` panicked on it (the `demo_mcap` fuzz target's first find).
    const ENDLESS_RECORD: &[u8] = b"\x89MCAP0\r\n\x01\xff\xff\xff\xff\xff\xff\xff\xff";

    #[test]
    fn a_record_longer_than_the_bound_is_an_error() {
        let first = messages(ENDLESS_RECORD, true).next();
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
        let first = messages(&file, true).next();
        assert!(
            matches!(first, Some(Err(mcap::McapError::RecordTooLarge { .. }))),
            "{first:?}"
        );
    }

    #[test]
    fn the_bound_grows_with_the_file_from_a_floor() {
        assert_eq!(record_limit(0), MIN_LIMIT);
        assert_eq!(record_limit(1 << 30), 64 << 30);
        assert_eq!(record_limit(usize::MAX), usize::MAX);
    }
}
