//! Writing files safely: to a temporary file beside the target, then an atomic rename,
//! so a crash or a full disk never leaves a half-written file in place of a good one.
//! Only a regular file (or none) is replaced so: a device, FIFO or socket is written to
//! directly (`-o /dev/null` discards, `/dev/full` reports a full disk), and a folder or
//! anything else is refused by name.

use std::fs::{self, File};
use std::io::{self, BufRead, Write};
use std::path::{Path, PathBuf};

use sha2::Digest;

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Remove the temporary files that killed writes to `path` left beside it
/// (`.NAME.PID.tmp` of a process no longer running), so they do not pile up. A live
/// process's file is its write in progress and is kept. Where the system cannot tell
/// (no `/proc`), a temporary file untouched for a day counts as left.
fn remove_stale_temps(path: &Path) {
    let (Some(name), Some(dir)) = (path.file_name(), path.parent()) else {
        return;
    };
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let prefix = format!(".{}.", name.to_string_lossy());
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let proc_fs = Path::new("/proc/self").exists();
    for entry in entries.flatten() {
        let file = entry.file_name();
        let file = file.to_string_lossy();
        let Some(pid) = file
            .strip_prefix(&prefix)
            .and_then(|rest| rest.strip_suffix(".tmp"))
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let stale = if proc_fs {
            !Path::new("/proc").join(pid.to_string()).exists()
        } else {
            entry
                .metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|age| age.as_secs() > 24 * 3600)
        };
        if stale && pid != std::process::id() {
            let p = entry.path();
            let _ = if p.is_dir() {
                fs::remove_dir_all(p)
            } else {
                fs::remove_file(p)
            };
        }
    }
}

/// What an output path holds, as far as writing it goes.
enum Target {
    /// A regular file, or nothing yet: replaced atomically.
    File,
    /// A character or block device, a FIFO or a socket: written in place.
    Stream,
}

/// What `path` is (links followed); a folder or any other kind is refused by name.
fn target(path: &Path) -> io::Result<Target> {
    let meta = match fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Target::File),
        Err(e) => return Err(e),
    };
    let kind = meta.file_type();
    if kind.is_file() {
        return Ok(Target::File);
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() || kind.is_block_device() || kind.is_fifo() || kind.is_socket() {
            return Ok(Target::Stream);
        }
    }
    let what = if kind.is_dir() {
        "a folder"
    } else {
        "neither a file nor a device"
    };
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{} is {what}: refusing to write over it; choose a file",
            path.display()
        ),
    ))
}

/// Write `bytes` to `path` atomically (temporary file + fsync + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Write through `fill` into a temporary file, then rename it over `path`. On any error
/// the temporary file is removed and `path` is left as it was. A device, FIFO or socket
/// at `path` is written directly (a rename would replace the node itself).
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut io::BufWriter<&File>) -> io::Result<()>,
) -> io::Result<()> {
    if let Target::Stream = target(path)? {
        let file = fs::OpenOptions::new().write(true).open(path)?;
        let mut w = io::BufWriter::new(&file);
        fill(&mut w)?;
        return w.flush();
    }
    remove_stale_temps(path);
    let tmp = temp_path(path);
    let result = (|| {
        let file = File::create(&tmp)?;
        {
            let mut w = io::BufWriter::new(&file);
            fill(&mut w)?;
            w.flush()?;
        }
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Fill a folder as a whole: `fill` writes into a temporary folder beside `dir`
/// (`.NAME.PID.tmp`), which then becomes `dir` by a rename when `dir` does not exist yet;
/// into an existing `dir` (which may hold other files) its files are moved one by one,
/// those named in `last` (an index of the others) after the rest. A run killed while
/// filling leaves `dir` as it was, and its temporary folder goes with the next write to
/// `dir`.
pub fn write_dir_atomic<T, E: From<io::Error>>(
    dir: &Path,
    last: &[&str],
    fill: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    remove_stale_temps(dir);
    let tmp = temp_path(dir);
    if tmp.exists() {
        fs::remove_dir_all(&tmp)?;
    }
    fs::create_dir_all(&tmp)?;
    let placed = fill(&tmp).and_then(|value| {
        if !dir.exists() {
            fs::rename(&tmp, dir)?;
            return Ok(value);
        }
        let mut names: Vec<_> = fs::read_dir(&tmp)?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<io::Result<_>>()?;
        // Files of `last` sort after the others, keeping their order.
        names.sort_by_key(|n| last.iter().position(|l| n.as_os_str() == *l));
        for name in names {
            fs::rename(tmp.join(&name), dir.join(&name))?;
        }
        fs::remove_dir(&tmp)?;
        Ok(value)
    });
    if placed.is_err() {
        let _ = fs::remove_dir_all(&tmp);
    }
    placed
}

/// The path as the file system resolves it: canonical where it exists, else its folder's
/// canonical path joined with its name (an output about to be created).
fn resolved(path: &Path) -> PathBuf {
    if let Ok(p) = fs::canonicalize(path) {
        return p;
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match (fs::canonicalize(parent), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => path.to_path_buf(),
    }
}

/// Refuse to write `output` when it is one of `inputs` (compared as resolved paths, so
/// `./a.json`, `dir/../a.json` and a link to it are the same file): writing would destroy
/// the input. The error names both.
pub fn refuse_input_as_output(output: &Path, inputs: &[&Path]) -> io::Result<()> {
    let out = resolved(output);
    match inputs.iter().find(|i| resolved(i) == out) {
        Some(input) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "the output {} is the input {}: writing it would destroy the input; choose \
                 another output",
                output.display(),
                input.display()
            ),
        )),
        None => Ok(()),
    }
}

/// Refuse to write `output` inside `folder`, an input folder that is read as a whole (a
/// bag folder, a dataset, a folder of trial files): the output would change what the input
/// holds, or replace one of its files. A `folder` that is not a folder covers nothing.
pub fn refuse_output_inside(output: &Path, folder: &Path) -> io::Result<()> {
    let Ok(dir) = fs::canonicalize(folder) else {
        return Ok(());
    };
    if !dir.is_dir() || !resolved(output).starts_with(&dir) {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "the output {} is inside the input folder {}: writing it would change the input; \
             choose an output outside it",
            output.display(),
            folder.display()
        ),
    ))
}

/// The most bytes a JSON file of each kind may hold. A file past its bound is refused
/// before a byte of it is read: junk costs no memory and no time. Far above any real file
/// (the samples' sessions are 1–2 MB, a 2 GB bag's tactile topics import to 13 MB, models
/// and specs are kilobytes to a few megabytes).
pub mod max_bytes {
    pub const SESSION: u64 = 4 << 30;
    pub const PROJECT: u64 = 1 << 30;
    pub const MODEL: u64 = 256 << 20;
    pub const SPEC: u64 = 64 << 20;
    /// A plan folder holds a copy of its session.
    pub const SWEEP: u64 = SESSION;
    /// A figure (`render-figure`), a frontier file or a result to compare with.
    pub const FIGURE: u64 = 256 << 20;
    pub const RESULT: u64 = PROJECT;
}

/// Open a JSON file to be parsed as it is read (`serde_json::from_reader`): refused when
/// longer than `max_bytes` (`what` names the kind of file in the error), buffered, and
/// past a UTF-8 byte-order mark, which some editors write and JSON parsers refuse.
pub fn open_json(path: &Path, max_bytes: u64, what: &str) -> io::Result<io::BufReader<File>> {
    let file = File::open(path)?;
    let len = file.metadata()?.len();
    if len > max_bytes {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "{len} bytes, more than the {} MiB a {what} may hold: not a {what}",
                max_bytes >> 20
            ),
        ));
    }
    let mut r = io::BufReader::with_capacity(1 << 16, file);
    if r.fill_buf()?.starts_with(BOM) {
        r.consume(BOM.len());
    }
    Ok(r)
}

/// The UTF-8 byte-order mark.
pub const BOM: &[u8] = b"\xEF\xBB\xBF";

/// `text` past a UTF-8 byte-order mark.
pub fn without_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// `sha256:` and the hex digest of `bytes`.
pub fn content_hash(bytes: &[u8]) -> String {
    let digest = sha2::Sha256::digest(bytes);
    let mut out = String::with_capacity(7 + 64);
    out.push_str("sha256:");
    for b in digest {
        out.push_str(&format!("{b:02x}"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_keeps_the_old_file() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.json");
        write_atomic(&p, b"old").unwrap();
        let r = write_atomic_with(&p, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("disk full"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read(&p).unwrap(), b"old");
        let leftovers = fs::read_dir(&dir).unwrap().count();
        assert_eq!(leftovers, 1, "the temporary file is removed");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporary_files_of_killed_writes_go_with_the_next_write() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-stale-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.json");
        // A process id above Linux's largest (2^22) never runs; process 1 always does.
        let dead = dir.join(".a.json.4194305.tmp");
        let live = dir.join(".a.json.1.tmp");
        let other_target = dir.join(".b.json.4194305.tmp");
        for f in [&dead, &live, &other_target] {
            fs::write(f, b"half").unwrap();
        }
        write_atomic(&p, b"new").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new");
        assert!(!dead.exists(), "the killed write's file is removed");
        if Path::new("/proc/self").exists() {
            assert!(live.exists(), "a running process's write is kept");
        }
        assert!(
            other_target.exists(),
            "another target's file is not touched"
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_folder_is_refused_and_a_fifo_written_in_place() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-kinds-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("out")).unwrap();
        let e = write_atomic(&dir.join("out"), b"x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("out") && e.contains("a folder"), "{e}");
        assert!(dir.join("out").is_dir());
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            let fifo = dir.join("fifo");
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if made.is_ok_and(|s| s.success()) {
                let reader = {
                    let fifo = fifo.clone();
                    std::thread::spawn(move || fs::read(fifo))
                };
                write_atomic(&fifo, b"through").unwrap();
                assert_eq!(reader.join().unwrap().unwrap(), b"through");
                let kind = fs::metadata(&fifo).unwrap().file_type();
                assert!(kind.is_fifo(), "the FIFO is still a FIFO");
            }
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_byte_order_mark_is_skipped_and_a_file_past_its_bound_refused() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-json-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.json");
        fs::write(&p, b"\xEF\xBB\xBF{\"a\": 1}").unwrap();
        let v: serde_json::Value =
            serde_json::from_reader(open_json(&p, 100, "test").unwrap()).unwrap();
        assert_eq!(v["a"], 1);
        let e = open_json(&p, 5, "test file").unwrap_err().to_string();
        assert!(e.contains("more than") && e.contains("test file"), "{e}");
        assert_eq!(without_bom("\u{feff}{}"), "{}");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_output_inside_an_input_folder_is_refused() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-inside-{}", std::process::id()));
        fs::create_dir_all(dir.join("bag")).unwrap();
        let bag = dir.join("bag");
        assert!(refuse_output_inside(&bag.join("metadata.yaml"), &bag).is_err());
        assert!(refuse_output_inside(&bag.join("sub").join("..").join("x.json"), &bag).is_err());
        assert!(refuse_output_inside(&dir.join("session.json"), &bag).is_ok());
        assert!(refuse_output_inside(&dir.join("bag.json"), &bag).is_ok());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_folder_is_filled_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-dir-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let out = dir.join("figures");
        let fill = |d: &Path| -> io::Result<()> {
            fs::write(d.join("a.svg"), b"a")?;
            fs::write(d.join("index.md"), b"a")
        };
        write_dir_atomic(&out, &["index.md"], fill).unwrap();
        assert_eq!(fs::read(out.join("index.md")).unwrap(), b"a");
        // A failing fill leaves the folder as it was and no temporary folder.
        fs::write(out.join("mine.txt"), b"keep").unwrap();
        let r = write_dir_atomic(&out, &["index.md"], |d: &Path| -> io::Result<()> {
            fs::write(d.join("a.svg"), b"half")?;
            Err(io::Error::other("killed"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read(out.join("a.svg")).unwrap(), b"a");
        // A killed run's temporary folder goes with the next write; other files stay.
        let killed = dir.join(".figures.4194305.tmp");
        fs::create_dir_all(&killed).unwrap();
        write_dir_atomic(&out, &["index.md"], |d: &Path| -> io::Result<()> {
            fs::write(d.join("a.svg"), b"b")?;
            fs::write(d.join("index.md"), b"b")
        })
        .unwrap();
        assert_eq!(fs::read(out.join("a.svg")).unwrap(), b"b");
        assert_eq!(fs::read(out.join("mine.txt")).unwrap(), b"keep");
        let left: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left, [std::ffi::OsString::from("figures")]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_by_any_spelling() {
        let dir = std::env::temp_dir().join(format!("tw-fsutil-in-{}", std::process::id()));
        fs::create_dir_all(dir.join("sub")).unwrap();
        let input = dir.join("rec.mcap");
        fs::write(&input, b"bag").unwrap();
        let other = dir.join("other.csv");
        let same = dir.join("sub").join("..").join("rec.mcap");
        let e = refuse_input_as_output(&same, &[&other, &input]).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains(&same.display().to_string()) && m.contains(&input.display().to_string()),
            "{m}"
        );
        #[cfg(unix)]
        {
            let link = dir.join("link.mcap");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            assert!(refuse_input_as_output(&link, &[&input]).is_err());
        }
        assert!(refuse_input_as_output(&dir.join("session.json"), &[&input]).is_ok());
        assert!(refuse_input_as_output(&other, &[&input]).is_ok());
        assert_eq!(fs::read(&input).unwrap(), b"bag");
        fs::remove_dir_all(&dir).unwrap();
    }
}
