//! Self-collision table values kept in a file (`self_tables.bin` in a robot folder, embedded
//! for the built-in Panda), so that a process starts with the tables its checks would
//! otherwise fill node by node (about 3 µs a node; the Panda's 159,301 nodes take 0.5 s).
//!
//! Each table's values are stored under its fingerprint
//! ([`super::pair_table::PairTable::fingerprint`]): a table takes stored values only when the
//! robot, the margins, the grid and the code that computes them are the ones they were
//! computed with, and otherwise fills itself as before.
//!
//! Layout (little-endian): the line `akl self tables 1\n`, the number of tables (u32), then
//! per table its 32-byte fingerprint, its number of nodes (u32) and one f32 per node.

use super::pair_table::Fingerprint;

/// The file's first bytes, with its layout's version.
const MAGIC: &[u8] = b"akl self tables 1\n";

/// Stored node values of self-collision tables, by fingerprint.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StoredTables {
    entries: Vec<(Fingerprint, Vec<f32>)>,
}

/// Why bytes are not a stored-tables file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StoredTablesError {
    /// The file does not begin as one.
    #[error("not a self-collision table file (it should begin with `akl self tables 1`; write one with `akl robot tables`)")]
    NotTables,
    /// The file ends inside a table, or runs on past the last.
    #[error("truncated or corrupt: {0}")]
    Corrupt(String),
}

impl StoredTables {
    /// The tables stored in `bytes`.
    pub fn parse(bytes: &[u8]) -> Result<StoredTables, StoredTablesError> {
        let mut rest = bytes
            .strip_prefix(MAGIC)
            .ok_or(StoredTablesError::NotTables)?;
        let count = take_u32(&mut rest, "the number of tables")?;
        let mut entries = Vec::new();
        for t in 0..count {
            let fingerprint: Fingerprint =
                take(&mut rest, 32, || format!("table {t}'s fingerprint"))?
                    .try_into()
                    .expect("took 32 bytes");
            let nodes = take_u32(&mut rest, "a table's number of nodes")? as usize;
            let raw = take(&mut rest, 4 * nodes, || {
                format!("table {t}'s {nodes} values")
            })?;
            let values = raw
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes")))
                .collect();
            entries.push((fingerprint, values));
        }
        if !rest.is_empty() {
            return Err(StoredTablesError::Corrupt(format!(
                "{} byte(s) after the last of {count} tables",
                rest.len()
            )));
        }
        Ok(StoredTables { entries })
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = MAGIC.to_vec();
        bytes.extend((self.entries.len() as u32).to_le_bytes());
        for (fingerprint, values) in &self.entries {
            bytes.extend(fingerprint);
            bytes.extend((values.len() as u32).to_le_bytes());
            for v in values {
                bytes.extend(v.to_le_bytes());
            }
        }
        bytes
    }

    /// Adds the values of the table with `fingerprint`.
    pub(super) fn push(&mut self, fingerprint: Fingerprint, values: Vec<f32>) {
        self.entries.push((fingerprint, values));
    }

    /// The values stored for the table with `fingerprint`.
    pub(super) fn get(&self, fingerprint: &Fingerprint) -> Option<&[f32]> {
        self.entries
            .iter()
            .find(|(f, _)| f == fingerprint)
            .map(|(_, v)| v.as_slice())
    }

    /// Number of tables stored.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no table is stored.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Number of node values stored, over all tables.
    pub fn nodes(&self) -> usize {
        self.entries.iter().map(|(_, v)| v.len()).sum()
    }
}

/// The next `n` bytes of `rest`, or an error naming `what` was cut short.
fn take<'b>(
    rest: &mut &'b [u8],
    n: usize,
    what: impl FnOnce() -> String,
) -> Result<&'b [u8], StoredTablesError> {
    if rest.len() < n {
        return Err(StoredTablesError::Corrupt(format!(
            "the file ends within {}",
            what()
        )));
    }
    let (head, tail) = rest.split_at(n);
    *rest = tail;
    Ok(head)
}

/// The next little-endian u32 of `rest`.
fn take_u32(rest: &mut &[u8], what: &str) -> Result<u32, StoredTablesError> {
    let bytes = take(rest, 4, || what.to_string())?;
    Ok(u32::from_le_bytes(bytes.try_into().expect("4 bytes")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_tables() -> StoredTables {
        let mut stored = StoredTables::default();
        stored.push([1; 32], vec![0.5, -0.25, 1e-3]);
        stored.push([2; 32], vec![]);
        stored
    }

    /// Written tables read back the same, each under its fingerprint.
    #[test]
    fn tables_read_back_as_written() {
        let stored = two_tables();
        let read = StoredTables::parse(&stored.to_bytes()).unwrap();
        assert_eq!(read, stored);
        assert_eq!(read.get(&[1; 32]), Some(&[0.5, -0.25, 1e-3][..]));
        assert_eq!(read.get(&[3; 32]), None);
        assert_eq!((read.len(), read.nodes()), (2, 3));
    }

    /// Other files, cut ones and ones with bytes past the last table are refused, saying
    /// where they go wrong.
    #[test]
    fn malformed_files_are_refused() {
        let bytes = two_tables().to_bytes();
        assert_eq!(
            StoredTables::parse(b"solid link0\n"),
            Err(StoredTablesError::NotTables)
        );
        for cut in [MAGIC.len() + 2, MAGIC.len() + 20, bytes.len() - 40] {
            let e = StoredTables::parse(&bytes[..cut]).unwrap_err();
            assert!(e.to_string().contains("ends within"), "{e}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        let e = StoredTables::parse(&longer).unwrap_err();
        assert!(
            e.to_string()
                .contains("1 byte(s) after the last of 2 tables"),
            "{e}"
        );
    }
}
