//! Writing ROS 2 bags: MCAP with CDR messages and their `.msg` schemas as rosbag2 stores
//! them, so that Foxglove and rerun read them without configuration (`prf export-mcap`).

use super::messages::definition;
use byteorder::LittleEndian;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Why a bag could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: cannot write {what}: {detail}")]
pub struct WriteError {
    pub path: PathBuf,
    pub what: String,
    pub detail: String,
}

/// An MCAP file being written; one channel per topic, created on its first message. It is
/// written beside its path and moved there by [`BagWriter::finish`]: an export that fails or is
/// killed leaves the previous file as it was.
pub struct BagWriter {
    w: mcap::Writer<BufWriter<File>>,
    tmp: tempfile::NamedTempFile,
    path: PathBuf,
    /// Topic → (channel, schema name, messages).
    channels: BTreeMap<String, (u16, &'static str, u64)>,
}

impl BagWriter {
    /// Starts the bag that [`BagWriter::finish`] puts at `path`.
    pub fn create(path: &Path) -> Result<Self, WriteError> {
        let fail = |what: &str, detail: String| WriteError {
            path: path.to_path_buf(),
            what: what.into(),
            detail,
        };
        let tmp = crate::atomic::temp_beside(path).map_err(|e| fail("the file", e.to_string()))?;
        let file = tmp
            .as_file()
            .try_clone()
            .map_err(|e| fail("the file", e.to_string()))?;
        let w = mcap::Writer::new(BufWriter::new(file))
            .map_err(|e| fail("the MCAP header", e.to_string()))?;
        Ok(BagWriter {
            w,
            tmp,
            path: path.to_path_buf(),
            channels: BTreeMap::new(),
        })
    }

    fn fail(&self, what: String, detail: impl ToString) -> WriteError {
        WriteError {
            path: self.path.clone(),
            what,
            detail: detail.to_string(),
        }
    }

    /// Writes `msg` of type `schema` on `topic` at `t_ns` (log and publish time).
    pub fn write<T: Serialize>(
        &mut self,
        topic: &str,
        schema: &'static str,
        t_ns: i64,
        msg: &T,
    ) -> Result<(), WriteError> {
        let channel = match self.channels.get_mut(topic) {
            Some((c, s, n)) if *s == schema => {
                *n += 1;
                *c
            }
            Some((_, s, _)) => {
                let s = *s;
                return Err(self.fail(
                    topic.to_string(),
                    format!("type {schema}, but the topic has {s}"),
                ));
            }
            None => {
                let text = definition(schema).ok_or_else(|| {
                    self.fail(topic.to_string(), format!("no definition of {schema}"))
                })?;
                let s = self
                    .w
                    .add_schema(schema, "ros2msg", text.as_bytes())
                    .map_err(|e| self.fail(format!("the schema {schema}"), e))?;
                let c = self
                    .w
                    .add_channel(s, topic, "cdr", &BTreeMap::new())
                    .map_err(|e| self.fail(format!("the channel {topic}"), e))?;
                self.channels.insert(topic.to_string(), (c, schema, 1));
                c
            }
        };
        // CDR little endian: the encapsulation header, then the message.
        let mut data = vec![0, 1, 0, 0];
        data.extend(
            cdr_encoding::to_vec::<T, LittleEndian>(msg)
                .map_err(|e| self.fail(format!("a message on {topic}"), e))?,
        );
        let t = t_ns.max(0) as u64;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: 0,
            log_time: t,
            publish_time: t,
        };
        self.w
            .write_to_known_channel(&header, &data)
            .map_err(|e| self.fail(format!("a message on {topic}"), e))
    }

    /// Messages written per topic, with their schema.
    pub fn counts(&self) -> Vec<(String, &'static str, u64)> {
        self.channels
            .iter()
            .map(|(t, (_, s, n))| (t.clone(), *s, *n))
            .collect()
    }

    /// Writes the summary and puts the complete file at its path.
    pub fn finish(mut self) -> Result<(), WriteError> {
        self.w
            .finish()
            .map_err(|e| self.fail("the summary".into(), e))?;
        let path = self.path.clone();
        let fail = |e: std::io::Error| WriteError {
            path: path.clone(),
            what: "the file".into(),
            detail: e.to_string(),
        };
        self.w
            .into_inner()
            .into_inner()
            .map_err(|e| fail(e.into_error()))?;
        crate::atomic::persist(self.tmp, &path).map_err(fail)
    }
}
