//! A bag's `.mcap` files: the file itself, or those a bag folder's metadata.yaml lists.

use std::path::{Path, PathBuf};

use crate::session::SessionError;
use crate::session::error::{read_text, shorten};

/// The `.mcap` files of a bag: the file itself, or those a bag folder's metadata.yaml lists.
pub fn bag_files(path: &Path) -> Result<Vec<PathBuf>, SessionError> {
    if !path.is_dir() {
        if !path.is_file() {
            return Err(SessionError::file(path, "no such file or folder"));
        }
        return Ok(vec![path.to_path_buf()]);
    }
    let meta = path.join("metadata.yaml");
    if !meta.is_file() {
        return Err(SessionError::file(
            path,
            "no metadata.yaml: not a ROS 2 bag folder as `ros2 bag record` writes it",
        ));
    }
    let text = read_text(&meta)?;
    let files = metadata_files(&text, &meta)?;
    files
        .into_iter()
        .map(|(line, name)| {
            let f = path.join(&name);
            if !name.ends_with(".mcap") {
                Err(SessionError::line(
                    &meta,
                    line,
                    format!("`{}` is not an .mcap file", shorten(&name)),
                ))
            } else if !f.is_file() {
                Err(SessionError::line(
                    &meta,
                    line,
                    format!("lists `{}`, which is not in the folder", shorten(&name)),
                ))
            } else {
                Ok(f)
            }
        })
        .collect()
}

/// A scalar of a `key: value` line, unquoted.
fn unquote(v: &str) -> &str {
    let v = v.trim();
    v.strip_prefix('\'')
        .and_then(|s| s.strip_suffix('\''))
        .or_else(|| v.strip_prefix('"').and_then(|s| s.strip_suffix('"')))
        .unwrap_or(v)
}

/// The storage checks and the split files, in order, of a rosbag2 metadata.yaml, with
/// the line of each. rosbag2 writes this file itself in a fixed block style, so the few
/// keys needed are read line by line rather than with a YAML parser.
fn metadata_files(text: &str, meta: &Path) -> Result<Vec<(usize, String)>, SessionError> {
    let lines: Vec<&str> = text.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let value_of = |key: &str| {
        lines.iter().enumerate().find_map(|(i, l)| {
            l.trim_start()
                .strip_prefix(key)
                .and_then(|rest| rest.strip_prefix(':'))
                .map(|v| (i + 1, unquote(v)))
        })
    };
    if let Some((line, storage)) = value_of("storage_identifier")
        && storage != "mcap"
    {
        return Err(SessionError::line(
            meta,
            line,
            format!(
                "the bag is stored as `{}`; only MCAP bags are read (convert it with \
                 `ros2 bag convert`)",
                shorten(storage)
            ),
        ));
    }
    if let Some((line, mode)) = value_of("compression_mode")
        && !mode.is_empty()
    {
        return Err(SessionError::line(
            meta,
            line,
            format!(
                "the bag is compressed per {} (compression_mode {}); decompress it with \
                 `ros2 bag decompress`, or record with MCAP's own chunk compression",
                mode.to_lowercase(),
                shorten(mode)
            ),
        ));
    }
    let Some(key) = lines
        .iter()
        .position(|l| l.trim_start().starts_with("relative_file_paths:"))
    else {
        return Err(SessionError::file(meta, "no `relative_file_paths` list"));
    };
    let rest = lines[key].trim_start()["relative_file_paths:".len()..].trim();
    let mut files = Vec::new();
    if let Some(flow) = rest.strip_prefix('[') {
        let inner = flow.strip_suffix(']').ok_or_else(|| {
            SessionError::line(meta, key + 1, "the list of files is not closed on its line")
        })?;
        files.extend(
            inner
                .split(',')
                .map(unquote)
                .filter(|s| !s.is_empty())
                .map(|s| (key + 1, s.to_string())),
        );
    } else {
        let key_indent = indent(lines[key]);
        for (i, l) in lines.iter().enumerate().skip(key + 1) {
            match l.trim_start().strip_prefix('-') {
                Some(item) if indent(l) >= key_indent => {
                    files.push((i + 1, unquote(item).to_string()))
                }
                _ => break,
            }
        }
    }
    if files.is_empty() {
        return Err(SessionError::line(meta, key + 1, "the bag lists no files"));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_lists_files_indented_or_not_and_in_flow_style() -> Result<(), SessionError> {
        let p = Path::new("metadata.yaml");
        let rosbag2 = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
                       relative_file_paths:\n    - b_0.mcap\n    - \"b_1.mcap\"\n  duration:\n";
        let names = |v: Vec<(usize, String)>| v.into_iter().map(|(_, n)| n).collect::<Vec<_>>();
        assert_eq!(names(metadata_files(rosbag2, p)?), ["b_0.mcap", "b_1.mcap"]);
        let compact = "x:\n  relative_file_paths:\n  - a.mcap\n  - 'c.mcap'\n  ros_distro: r\n";
        assert_eq!(names(metadata_files(compact, p)?), ["a.mcap", "c.mcap"]);
        let flow = "relative_file_paths: [a.mcap, b.mcap]\n";
        assert_eq!(names(metadata_files(flow, p)?), ["a.mcap", "b.mcap"]);
        let sqlite = "storage_identifier: sqlite3\nrelative_file_paths:\n- a.db3\n";
        let e = metadata_files(sqlite, p).unwrap_err().to_string();
        assert!(
            e.contains("metadata.yaml:1:") && e.contains("sqlite3"),
            "{e}"
        );
        Ok(())
    }
}
