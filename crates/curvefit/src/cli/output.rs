//! All-or-nothing outputs: every output of a command (files, devices, standard output) is
//! produced in full before any is committed, and a failure removes what was staged.
//!
//! Order of a commit:
//! 1. every regular file is written to a temporary sibling (`.NAME.PID.K.tmp`) and flushed;
//! 2. the streams — standard output, devices, FIFOs, which cannot be taken back once written —
//!    are written (when there are several, all but the last are rendered into memory first, so
//!    a rendering cannot fail between two of them);
//! 3. the temporaries are renamed over their targets (on Linux a target that is a regular file is
//!    exchanged with its temporary, and the temporary — now the old content — removed:
//!    `put_in_place`).
//!
//! A failure in 1 or 2 removes every temporary, so no file is created or changed; the streams
//! come before the renames because a write to a full disk or a closed pipe is far likelier than
//! a rename in a directory where a temporary was just created. Two outputs naming the same file
//! (`-o X --svg X`, `./X`, a symlink to X) are refused before anything is written; a device may
//! be named twice (`-o /dev/null --svg /dev/null`).

use std::io::Write;
use std::path::{Path, PathBuf};

use super::InputError;

/// Something that writes one output's content.
pub type Writer<'a> = Box<dyn FnOnce(&mut dyn Write) -> std::io::Result<()> + 'a>;

/// A writer of fixed bytes.
pub fn bytes_writer<'a>(bytes: Vec<u8>) -> Writer<'a> {
    Box::new(move |w: &mut dyn Write| w.write_all(&bytes))
}

/// Buffer size of every output writer.
const BUFFER: usize = 1 << 16;

/// Where an output goes.
enum Target {
    /// Standard output (no `-o`, or `-o -`).
    Stdout,
    /// A path: a regular file (renamed into place) or a device/FIFO (written in place).
    Path(PathBuf),
}

struct Item<'a> {
    /// The flag that named the output (`-o`, `--svg`, `--obj`, `--out`), for messages.
    flag: String,
    target: Target,
    /// The resolved identity of a path (for refusing duplicates), `None` for standard output.
    identity: Option<PathBuf>,
    write: Writer<'a>,
}

/// The outputs of one command, committed together by [`Outputs::commit`].
#[derive(Default)]
pub struct Outputs<'a> {
    items: Vec<Item<'a>>,
}

/// The file a path names: its canonical path, or for a file yet to be created its canonical
/// parent joined with its name (so `./x`, `d/../x` and a symlink to `x` all compare equal).
fn identity(path: &Path) -> PathBuf {
    if let Ok(p) = std::fs::canonicalize(path) {
        return p;
    }
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    match (std::fs::canonicalize(parent), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => path.to_path_buf(),
    }
}

/// A device, FIFO or socket: written in place (renaming a temporary over it would replace the
/// device with a regular file), and never taken back.
fn is_stream(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

fn describe(target: &Target) -> String {
    match target {
        Target::Stdout => "standard output".to_string(),
        Target::Path(p) => p.display().to_string(),
    }
}

impl<'a> Outputs<'a> {
    /// No outputs yet.
    pub fn new() -> Self {
        Outputs { items: Vec::new() }
    }

    /// Adds an output named by `flag`: `path` `None` or `-` is standard output.
    ///
    /// # Errors
    /// When another output already names the same file (or both name standard output).
    pub fn add(
        &mut self,
        flag: &str,
        path: Option<&Path>,
        write: Writer<'a>,
    ) -> Result<(), InputError> {
        let target = match path {
            None => Target::Stdout,
            Some(p) if p.as_os_str() == "-" => Target::Stdout,
            Some(p) => Target::Path(p.to_path_buf()),
        };
        let id = match &target {
            Target::Stdout => None,
            Target::Path(p) => Some(identity(p)),
        };
        let device = matches!(&target, Target::Path(p) if is_stream(p));
        for other in &self.items {
            let same = match (&id, &other.identity) {
                (None, None) => true,
                (Some(a), Some(b)) => a == b && !device,
                _ => false,
            };
            if same {
                return Err(InputError::new(
                    flag,
                    format!(
                        "{} is also the output of {}: give each output its own file",
                        describe(&target),
                        other.flag
                    ),
                ));
            }
        }
        self.items.push(Item {
            flag: flag.to_string(),
            target,
            identity: id,
            write,
        });
        Ok(())
    }

    /// Writes every output, all or nothing (see the module docs).
    ///
    /// # Errors
    /// The first write error, naming the output's flag and target; nothing was created or
    /// changed unless the error happened while renaming.
    pub fn commit(self, stdout: &mut dyn Write) -> Result<(), InputError> {
        let mut temps: Vec<(PathBuf, PathBuf, String)> = Vec::new();
        let cleanup = |temps: &[(PathBuf, PathBuf, String)]| {
            for (t, _, _) in temps {
                let _ = std::fs::remove_file(t);
            }
        };
        let fail = |flag: &str, target: &str, e: std::io::Error| {
            InputError::new(flag, format!("cannot write {target}: {e}"))
        };
        let mut streams: Vec<Item<'a>> = Vec::new();
        for (k, item) in self.items.into_iter().enumerate() {
            let path = match &item.target {
                Target::Path(p) if !is_stream(p) => p.clone(),
                _ => {
                    streams.push(item);
                    continue;
                }
            };
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "out".into());
            let tmp = path.with_file_name(format!(".{name}.{}.{k}.tmp", std::process::id()));
            let result = std::fs::File::create(&tmp).and_then(|f| {
                let mut w = std::io::BufWriter::with_capacity(BUFFER, f);
                (item.write)(&mut w)?;
                w.flush()
            });
            if let Err(e) = result {
                let _ = std::fs::remove_file(&tmp);
                cleanup(&temps);
                return Err(fail(&item.flag, &path.display().to_string(), e));
            }
            temps.push((tmp, path, item.flag));
        }
        // All streams but the last are rendered into memory first: writing one and then
        // failing to render the next would leave the first committed.
        let last = streams.len().saturating_sub(1);
        for item in streams.iter_mut().take(last) {
            let write = std::mem::replace(&mut item.write, bytes_writer(Vec::new()));
            let mut buf = Vec::new();
            if let Err(e) = write(&mut buf) {
                cleanup(&temps);
                return Err(fail(&item.flag, &describe(&item.target), e));
            }
            item.write = bytes_writer(buf);
        }
        for item in streams {
            let what = describe(&item.target);
            let write = item.write;
            let result = match &item.target {
                Target::Stdout => {
                    let mut w = std::io::BufWriter::with_capacity(BUFFER, &mut *stdout);
                    write(&mut w).and_then(|_| w.flush())
                }
                Target::Path(p) => std::fs::OpenOptions::new()
                    .write(true)
                    .open(p)
                    .and_then(|f| {
                        let mut w = std::io::BufWriter::with_capacity(BUFFER, f);
                        write(&mut w)?;
                        w.flush()
                    }),
            };
            let result = result.and_then(|_| match item.target {
                Target::Stdout => stdout.flush(),
                Target::Path(_) => Ok(()),
            });
            if let Err(e) = result {
                cleanup(&temps);
                let flag = match item.target {
                    Target::Stdout => "",
                    Target::Path(_) => &item.flag,
                };
                return Err(fail(flag, &what, e));
            }
        }
        for (i, (tmp, path, flag)) in temps.iter().enumerate() {
            if let Err(e) = put_in_place(tmp, path) {
                cleanup(&temps[i..]);
                return Err(fail(flag, &path.display().to_string(), e));
            }
        }
        Ok(())
    }
}

/// Renames the staged `tmp` to `path`, atomically: a reader of `path` sees its old content or the
/// new, never neither. On Linux a regular file at `path` is exchanged with `tmp` instead
/// (`renameat2` with `RENAME_EXCHANGE`) and its old content, now at `tmp`, removed: renaming over
/// an existing file makes ext4 (`auto_da_alloc`, on by default) allocate and start writing back
/// the new file's blocks inside the rename, which held a 52.7 MB JSON output's rename for
/// 36–40 ms; exchanged, the data is written back as any new file's is, and the old content's
/// removal takes ~13 ms. Anything else at `path` (nothing, a symbolic link, a directory), and a
/// file system that cannot exchange, gets a plain rename and its errors.
fn put_in_place(tmp: &Path, path: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file()) {
        use rustix::fs::{renameat_with, RenameFlags, CWD};
        if renameat_with(CWD, tmp, CWD, path, RenameFlags::EXCHANGE).is_ok() {
            // The output is in place; what is left at `tmp` is the replaced content. (Were it
            // not removable, the committed output would still be right: not an error.)
            let _ = std::fs::remove_file(tmp);
            return Ok(());
        }
    }
    std::fs::rename(tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("curvefit-output-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn the_same_file_twice_is_refused() {
        let d = scratch("same");
        let a = d.join("a.json");
        let mut o = Outputs::new();
        o.add("-o", Some(&a), bytes_writer(b"1".to_vec())).unwrap();
        let dotted = d.join(".").join("a.json");
        let e = o
            .add("--svg", Some(&dotted), bytes_writer(b"2".to_vec()))
            .unwrap_err();
        assert_eq!(e.field, "--svg");
        assert!(e.message.contains("-o"), "{e}");
        let mut o = Outputs::new();
        o.add("-o", None, bytes_writer(vec![])).unwrap();
        assert!(o
            .add("--svg", Some(Path::new("-")), bytes_writer(vec![]))
            .is_err());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_failing_output_leaves_no_file() {
        let d = scratch("fail");
        let a = d.join("a.json");
        let mut o = Outputs::new();
        o.add("-o", Some(&a), bytes_writer(b"1".to_vec())).unwrap();
        o.add(
            "--svg",
            Some(&d.join("b.svg")),
            Box::new(|_: &mut dyn Write| Err(std::io::Error::other("boom"))),
        )
        .unwrap();
        let e = o.commit(&mut Vec::new()).unwrap_err();
        assert_eq!(e.field, "--svg");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
        let _ = std::fs::remove_dir_all(&d);
    }

    /// The names in `d`, sorted.
    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// One output committed to `path` with `content`.
    fn commit_one(path: &Path, content: &[u8]) -> Result<(), InputError> {
        let mut o = Outputs::new();
        o.add("-o", Some(path), bytes_writer(content.to_vec()))?;
        o.commit(&mut Vec::new())
    }

    /// [`put_in_place`]: a regular file is replaced by the new content and its old content leaves
    /// nothing behind (the exchange's temporary removed); a symbolic link is replaced as `rename`
    /// replaces it (the link, not its target); a directory is refused and left as it was.
    #[test]
    fn replacing_leaves_the_new_content_and_nothing_else() {
        let d = scratch("replace");
        let a = d.join("a.json");
        commit_one(&a, b"old").unwrap();
        commit_one(&a, b"new").unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"new");
        assert_eq!(names(&d), ["a.json"]);
        #[cfg(unix)]
        {
            let target = d.join("target.json");
            std::fs::write(&target, b"kept").unwrap();
            let link = d.join("link.json");
            std::os::unix::fs::symlink(&target, &link).unwrap();
            commit_one(&link, b"through").unwrap();
            assert_eq!(std::fs::read(&target).unwrap(), b"kept");
            assert!(std::fs::symlink_metadata(&link).unwrap().is_file());
            assert_eq!(std::fs::read(&link).unwrap(), b"through");
        }
        let dir = d.join("dir.json");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("inside"), b"x").unwrap();
        let e = commit_one(&dir, b"no").unwrap_err();
        assert_eq!(e.field, "-o");
        assert_eq!(std::fs::read(dir.join("inside")).unwrap(), b"x");
        assert!(
            names(&d).iter().all(|n| !n.ends_with(".tmp")),
            "{:?}",
            names(&d)
        );
        let _ = std::fs::remove_dir_all(&d);
    }
}
