//! Sequences: which frames of a path camera to render (`--frames`), the run's task list
//! (every selected camera, each at each of its frames, in order) and the share of it one
//! process renders (`--shard K/N`).

use std::ops::RangeInclusive;

use penumbra::{Camera, Scene};

use crate::failure::{invalid, Failure};

/// `--frames`: `all`, or the frames `first..=last` taking every `step`-th.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frames {
    All,
    Range { first: i64, last: i64, step: u64 },
}

impl std::fmt::Display for Frames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Frames::All => f.write_str("all"),
            Frames::Range {
                first,
                last,
                step: 1,
            } => write!(f, "{first}:{last}"),
            Frames::Range { first, last, step } => write!(f, "{first}:{last}:{step}"),
        }
    }
}

/// `--shard K/N`: the tasks whose index is K modulo N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u64,
    pub count: u64,
}

impl Shard {
    /// True when task `i` (0-based, in the run's order) is this shard's.
    pub fn takes(&self, i: usize) -> bool {
        i as u64 % self.count == self.index
    }
}

/// One image of the run: a camera (by name; `None` for the scene's default) at a frame of
/// its path, or a still camera (`frame: None`).
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub camera: Option<String>,
    pub frame: Option<i64>,
    /// The camera of a path's frame; `None` for a still camera, rendered by its name.
    pub view: Option<Camera>,
}

pub fn parse_frames(s: &str) -> Result<Frames, String> {
    if s == "all" {
        return Ok(Frames::All);
    }
    let expected = "expected A:B (both included), A:B:STEP, A, or all";
    let parts: Vec<&str> = s.split(':').map(str::trim).collect();
    let int = |p: &str| {
        p.parse::<i64>()
            .map_err(|_| format!("`{p}` is not a frame: {expected}"))
    };
    let (first, last, step) = match parts[..] {
        [a] => (int(a)?, int(a)?, 1),
        [a, b] => (int(a)?, int(b)?, 1),
        [a, b, step] => {
            let step = step
                .parse::<u64>()
                .ok()
                .filter(|&n| n >= 1)
                .ok_or_else(|| {
                    format!("the step must be a whole number of at least 1, not `{step}`")
                })?;
            (int(a)?, int(b)?, step)
        }
        _ => return Err(expected.to_owned()),
    };
    if first > last {
        return Err(format!(
            "no frames from {first} to {last} (the first is after the last)"
        ));
    }
    Ok(Frames::Range { first, last, step })
}

pub fn parse_shard(s: &str) -> Result<Shard, String> {
    let expected = "expected K/N: shard K (from 0) of N";
    let (k, n) = s.split_once('/').ok_or(expected)?;
    let (index, count) = match (k.trim().parse::<u64>(), n.trim().parse::<u64>()) {
        (Ok(k), Ok(n)) => (k, n),
        _ => return Err(expected.to_owned()),
    };
    if count == 0 {
        return Err("N must be at least 1".to_owned());
    }
    if index >= count {
        return Err(format!(
            "K counts from 0, so shard {index} of {count} does not exist (K is 0 to {})",
            count - 1
        ));
    }
    Ok(Shard { index, count })
}

/// The run's tasks: each of `views` (camera names; `None`, the scene's default), a path
/// camera at each frame `frames` picks (all by default), a still camera once.
pub fn tasks(
    views: &[Option<String>],
    frames: Option<Frames>,
    scene: &Scene,
) -> Result<Vec<Task>, Failure> {
    let mut out = Vec::new();
    for view in views {
        let name = view
            .clone()
            .or_else(|| scene.world.cameras().first().map(|(n, _)| n.clone()));
        let path = name.as_deref().and_then(|n| scene.path(n));
        let Some(path) = path else {
            if frames.is_some() {
                let name = name.as_deref().unwrap_or("camera");
                return Err(invalid(format!(
                    "--frames: camera `{name}` is a still camera (it has no keys or path)"
                )));
            }
            out.push(Task {
                camera: view.clone(),
                frame: None,
                view: None,
            });
            continue;
        };
        let name = name.unwrap_or_default();
        let range = path.frames();
        for frame in pick(frames, &range).map_err(|()| {
            invalid(format!(
                "--frames {}: camera `{name}` has frames {} to {}",
                frames.unwrap_or(Frames::All),
                range.start(),
                range.end()
            ))
        })? {
            out.push(Task {
                camera: Some(name.clone()),
                frame: Some(frame),
                // A checked path has a camera at each of its frames.
                view: Some(path.camera(frame).ok_or_else(|| {
                    invalid(format!("camera `{name}` has no camera at frame {frame}"))
                })?),
            });
        }
    }
    Ok(out)
}

/// The frames of `range` that `frames` picks; `Err` when it asks for one outside.
fn pick(frames: Option<Frames>, range: &RangeInclusive<i64>) -> Result<Vec<i64>, ()> {
    match frames.unwrap_or(Frames::All) {
        Frames::All => Ok(range.clone().collect()),
        Frames::Range { first, last, step } => {
            if !range.contains(&first) || !range.contains(&last) {
                return Err(());
            }
            Ok((first..=last)
                .step_by(usize::try_from(step).unwrap_or(usize::MAX))
                .collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_read_like_blenders() {
        let r = |first, last, step| Ok(Frames::Range { first, last, step });
        assert_eq!(parse_frames("all"), Ok(Frames::All));
        assert_eq!(parse_frames("1:24"), r(1, 24, 1));
        assert_eq!(parse_frames("0:119:10"), r(0, 119, 10));
        assert_eq!(parse_frames("7"), r(7, 7, 1));
        assert_eq!(parse_frames("-5:-1"), r(-5, -1, 1));
        for bad in ["", "a:b", "5:1", "1:5:0", "1:2:3:4", "1:5:-1"] {
            assert!(parse_frames(bad).is_err(), "{bad}");
        }
        let picked = pick(
            Some(Frames::Range {
                first: 0,
                last: 10,
                step: 4,
            }),
            &(0..=10),
        );
        assert_eq!(picked, Ok(vec![0, 4, 8]));
        assert_eq!(
            pick(
                Some(Frames::Range {
                    first: 0,
                    last: 11,
                    step: 1
                }),
                &(0..=10)
            ),
            Err(())
        );
        assert_eq!(pick(None, &(3..=5)), Ok(vec![3, 4, 5]));
    }

    #[test]
    fn shards_split_the_tasks_without_overlap() {
        assert_eq!(parse_shard("1/4"), Ok(Shard { index: 1, count: 4 }));
        assert!(parse_shard("5/4").unwrap_err().contains("0 to 3"));
        assert!(parse_shard("4/4").is_err());
        assert!(parse_shard("0/0").unwrap_err().contains("at least 1"));
        assert!(parse_shard("1").is_err() && parse_shard("-1/4").is_err());
        let shards: Vec<Shard> = (0..4).map(|k| Shard { index: k, count: 4 }).collect();
        for i in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.takes(i)).count(), 1, "task {i}");
        }
    }
}
