//! An error's cause chain as users read it: the command's `error:` /
//! `caused by:` lines, batch mode's one-line messages and Python's
//! `LodgenError` all come from [`error_parts`], so none of them says the
//! same thing twice.

/// The messages of `e`'s cause chain, outermost first, without repeats:
/// a cause whose text the message before it already ends with is left out
/// (an I/O error shown in its parent's text and kept as its source), and a
/// cause that starts with what the message before it ends with (the
/// context `reading FILE` over the reader's `FILE:12: what`) is joined to
/// it from there: `reading FILE:12: what`.
pub fn error_parts(e: &anyhow::Error) -> Vec<String> {
    let mut parts: Vec<String> = Vec::new();
    for cause in e.chain() {
        let text = cause.to_string();
        let Some(last) = parts.last_mut() else {
            parts.push(text);
            continue;
        };
        if text.is_empty() || last.ends_with(&text) {
            continue;
        }
        match overlap(last, &text) {
            Some(n) => last.push_str(&text[n..]),
            None => parts.push(text),
        }
    }
    parts
}

/// [`error_parts`] on one line, joined by `": "`.
pub fn error_line(e: &anyhow::Error) -> String {
    error_parts(e).join(": ")
}

/// The length of the longest end of `parent` that `child` starts with,
/// where that end is a whole word of `parent` (it starts the text or
/// follows a space) and `child` goes on with `:` after it.
fn overlap(parent: &str, child: &str) -> Option<usize> {
    let starts = std::iter::once(0).chain(
        parent
            .char_indices()
            .filter(|&(_, c)| c == ' ')
            .map(|(i, _)| i + 1),
    );
    for start in starts {
        let end = &parent[start..];
        if !end.is_empty() && child.starts_with(end) && child[end.len()..].starts_with(':') {
            return Some(end.len());
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    fn chain(messages: &[&str]) -> anyhow::Error {
        let mut it = messages.iter().rev();
        let mut e = anyhow::anyhow!(it.next().copied().unwrap_or_default().to_string());
        for m in it {
            e = e.context(m.to_string());
        }
        e
    }

    #[test]
    fn a_context_naming_the_file_is_joined_to_the_readers_place() {
        let e = chain(&["reading in/a b.obj", "in/a b.obj:3: vertex is not finite"]);
        assert_eq!(
            error_parts(&e),
            ["reading in/a b.obj:3: vertex is not finite"]
        );
        let e = chain(&["reading x.obj", "x.obj: no triangles in the file"]);
        assert_eq!(error_line(&e), "reading x.obj: no triangles in the file");
    }

    #[test]
    fn a_cause_already_in_its_parents_text_is_left_out() {
        let io = std::io::Error::new(std::io::ErrorKind::PermissionDenied, "denied");
        let e: anyhow::Error = Err::<(), _>(io)
            .context("out/x.glb: denied")
            .context("writing out/x.glb")
            .unwrap_err();
        assert_eq!(error_line(&e), "writing out/x.glb: denied");
    }

    #[test]
    fn unrelated_causes_stay_apart() {
        let e = chain(&[
            "writing the report r.json",
            "Permission denied (os error 13)",
        ]);
        assert_eq!(
            error_parts(&e),
            [
                "writing the report r.json",
                "Permission denied (os error 13)"
            ]
        );
        // a word ending the parent that the cause merely starts with
        let e = chain(&["simplifying mesh", "mesh 0 (\"a\"): empty"]);
        assert_eq!(error_parts(&e).len(), 2);
        let e = chain(&["reading x.obj", "x.obj.bak: other file"]);
        assert_eq!(error_parts(&e).len(), 2);
    }
}
