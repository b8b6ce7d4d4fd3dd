//! Errors in words.

/// `e` and its sources in one line, "error: its source: that one's source", as the command line
/// prints an error chain (for messages carried on as text: another rank's, a table's cell).
pub fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut next = e.source();
    while let Some(cause) = next {
        text.push_str(": ");
        text.push_str(&cause.to_string());
        next = cause.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("reading x")]
    struct Outer(#[source] std::io::Error);

    #[test]
    fn a_chain_reads_outer_to_inner() {
        let inner = std::io::Error::other("gone");
        assert_eq!(chain(&inner), "gone");
        assert_eq!(chain(&Outer(inner)), "reading x: gone");
    }
}
