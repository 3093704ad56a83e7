//! `--camera`: which of the scene's cameras to render. A name, a comma list, `all`, or name
//! patterns where `*` matches any run of characters and `?` any one character.

use penumbra::World;

use crate::failure::{invalid, Failure};

/// The cameras `spec` names, in the order given (each pattern's matches in file order), each
/// once. `None` for no `--camera`: the scene's default view. A plain name is passed through
/// unchecked (rendering reports an unknown one with the known names); a pattern that matches
/// nothing is an error here.
pub fn select(spec: Option<&str>, world: &World) -> Result<Vec<Option<String>>, Failure> {
    let Some(spec) = spec else {
        return Ok(vec![None]);
    };
    let known: Vec<&str> = world.cameras().iter().map(|(n, _)| n.as_str()).collect();
    let mut chosen: Vec<String> = Vec::new();
    for item in spec.split(',').map(str::trim) {
        let names: Vec<String> = if item.is_empty() {
            return Err(invalid(format!("--camera: an empty name in `{spec}`")));
        } else if item == "all" {
            known.iter().map(|n| n.to_string()).collect()
        } else if item.contains(['*', '?']) {
            let matches: Vec<String> = known
                .iter()
                .filter(|n| glob(item, n))
                .map(|n| n.to_string())
                .collect();
            if matches.is_empty() {
                return Err(invalid(format!(
                    "--camera: no camera matches `{item}` (known: {})",
                    known.join(", ")
                )));
            }
            matches
        } else {
            vec![item.to_owned()]
        };
        for n in names {
            if !chosen.contains(&n) {
                chosen.push(n);
            }
        }
    }
    Ok(chosen.into_iter().map(Some).collect())
}

/// True when `name` matches `pattern` (`*`: any run of characters, `?`: one character).
fn glob(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // matches[j]: the pattern so far matches the first j characters of the name.
    let mut matches = vec![false; n.len() + 1];
    matches[0] = true;
    for &pc in &p {
        let mut next = vec![false; n.len() + 1];
        if pc == '*' {
            let mut any = false;
            for j in 0..=n.len() {
                any |= matches[j];
                next[j] = any;
            }
        } else {
            for j in 1..=n.len() {
                next[j] = matches[j - 1] && (pc == '?' || pc == n[j - 1]);
            }
        }
        matches = next;
    }
    matches[n.len()]
}

#[cfg(test)]
mod tests {
    use super::glob;

    #[test]
    fn globs_match_runs_and_single_characters() {
        assert!(glob("*", ""));
        assert!(glob("side*", "side_left"));
        assert!(glob("*left", "side_left"));
        assert!(glob("s?de", "side"));
        assert!(glob("a*b*c", "aXXbYc"));
        assert!(!glob("a*b*c", "aXXbY"));
        assert!(!glob("s?de", "sde"));
        assert!(!glob("front", "front2"));
        assert!(glob("é*", "éa"));
    }
}
