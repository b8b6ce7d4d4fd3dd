//! Progress bars of long commands (on stderr, drawn on a terminal only).

/// A progress bar of `len` steps named `what` on stderr (drawn on a terminal only).
pub fn bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    let template = format!("{{bar:30}} {what} {{pos}}/{{len}} [{{elapsed_precise}} < {{eta_precise}}]");
    bar.set_style(
        indicatif::ProgressStyle::with_template(&template).unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}
