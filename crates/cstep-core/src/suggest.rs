//! "Did you mean …?" for a name that is not one of the names a reader knows: a misspelt field of
//! a JSON message or a misspelt parameter is refused, and the refusal names the known name the
//! user most likely meant, so a typo is fixed from the error alone.
//!
//! Similarity is the Jaro similarity with the threshold clap uses for its own suggestions
//! (`strsim`, already in the tree through clap): short misspellings (`pos` for `position`,
//! `linaer` for `linear`, `horizn` for `horizon`) clear it, unrelated names do not.

/// The least Jaro similarity at which a known name is suggested (clap's threshold).
const THRESHOLD: f64 = 0.7;

/// The known name most similar to `given`, if any is similar enough to be a likely meaning
/// (the first of equally similar ones).
pub fn nearest<'a>(given: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    known
        .into_iter()
        .map(|name| (strsim::jaro(given, name), name))
        .filter(|(similarity, _)| *similarity >= THRESHOLD)
        .fold(None, |best: Option<(f64, &str)>, candidate| match best {
            Some(b) if b.0 >= candidate.0 => Some(b),
            _ => Some(candidate),
        })
        .map(|(_, name)| name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn misspellings_find_the_name_meant_and_unrelated_names_none() {
        let pose = ["position", "orientation"];
        assert_eq!(nearest("pos", pose), Some("position"));
        assert_eq!(nearest("orientaton", pose), Some("orientation"));
        assert_eq!(nearest("linaer", ["linear", "angular"]), Some("linear"));
        assert_eq!(
            nearest("horizn", ["horizon", "seed", "steps"]),
            Some("horizon")
        );
        assert_eq!(nearest("velocity", pose), None);
        assert_eq!(nearest("q", ["x", "y", "z", "w"]), None);
        assert_eq!(nearest("x", []), None);
    }
}
