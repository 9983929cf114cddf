//! Reading a ROS 2 bag stored as MCAP: a `.mcap` file, or a bag folder as `ros2 bag record`
//! writes it (`metadata.yaml` and one or more `.mcap` files, read in the order the metadata
//! lists them). Only the topics the spec names are decoded, each checked against its
//! definition in the bag; the others are skipped whatever their type.
//!
//! Time is the bag time of a message (its MCAP log time, ns since the epoch): every topic
//! then shares one clock, which is also the clock of a windows CSV.
//!
//! The folder: `metadata` finds a bag's files, `topics` the topics the spec reads and
//! their checks, `file` streams one MCAP file (its records framed and checked in
//! `records`), and `messages` decodes each message into its topic's rows.

mod file;
mod messages;
mod metadata;
mod records;
mod topics;

use std::path::Path;

use super::SessionError;
use super::spec::ImportSpec;
use file::read_file;
pub use metadata::bag_files;
pub(crate) use topics::{Role, allowed, roles, type_fits};

/// The messages of one tactile topic: one row of `width` values per stamp.
#[derive(Debug, Default)]
pub struct TactileTopic {
    pub topic: String,
    /// Indices of the spec's sensors read from this topic.
    pub sensors: Vec<usize>,
    /// Values per message: the end of the last sensor's slice.
    pub width: usize,
    pub stamps: Vec<u64>,
    pub values: Vec<f64>,
}

impl TactileTopic {
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.width..(i + 1) * self.width]
    }
}

/// The named joints' positions, one row per `JointState` message.
#[derive(Debug, Default)]
pub struct JointTopic {
    pub topic: String,
    pub stamps: Vec<u64>,
    pub values: Vec<f64>,
}

/// The decoded topics of a bag.
#[derive(Debug, Default)]
pub struct Bag {
    pub tactile: Vec<TactileTopic>,
    pub joints: Option<JointTopic>,
    /// (bag time, text) of each message of the events topic.
    pub events: Vec<(u64, String)>,
    /// First and last bag time of any message.
    pub span: Option<(u64, u64)>,
}

/// Read the topics the spec names from every file of the bag at `path`.
pub fn read(path: &Path, spec: &ImportSpec, events: Option<&str>) -> Result<Bag, SessionError> {
    let files = bag_files(path)?;
    let roles = roles(spec, events)?;
    let mut bag = Bag::default();
    for (topic, role) in &roles {
        match role {
            Role::Tactile(_) => {
                let sensors: Vec<usize> = (0..spec.sensors.len())
                    .filter(|&s| spec.sensors[s].topic.as_deref() == Some(topic))
                    .collect();
                let width = sensors
                    .iter()
                    .map(|&s| spec.sensors[s].range_in_message().end)
                    .max()
                    .unwrap_or(0);
                bag.tactile.push(TactileTopic {
                    topic: topic.clone(),
                    sensors,
                    width,
                    ..Default::default()
                });
            }
            Role::Joints => {
                bag.joints = Some(JointTopic {
                    topic: topic.clone(),
                    ..Default::default()
                })
            }
            Role::Events => {}
        }
    }
    // Every topic of the bag with its type, to name them when a spec topic is missing.
    let mut seen: Vec<(String, String)> = Vec::new();
    for file in &files {
        read_file(file, spec, &roles, &mut bag, &mut seen)?;
    }
    for (topic, role) in &roles {
        let messages = match role {
            Role::Tactile(i) => bag.tactile[*i].stamps.len(),
            Role::Joints => bag.joints.as_ref().map_or(0, |j| j.stamps.len()),
            Role::Events => bag.events.len(),
        };
        let what = role.what();
        if messages == 0 && seen.iter().any(|(t, _)| t == topic) {
            return Err(SessionError::topic(
                path,
                topic,
                None,
                format!("the spec's {what} is in the bag but holds no messages"),
            ));
        }
        if !seen.iter().any(|(t, _)| t == topic) {
            let listed: Vec<String> = seen.iter().map(|(t, ty)| format!("{t} ({ty})")).collect();
            return Err(SessionError::topic(
                path,
                topic,
                None,
                format!(
                    "the spec's {what} is not in the bag; its topics are: {}",
                    if listed.is_empty() {
                        "none".to_string()
                    } else {
                        listed.join(", ")
                    }
                ),
            ));
        }
    }
    Ok(bag)
}
