//! The README's Rust example compiles (the module below) and is, line for line, the text the
//! README shows (the test): an API change that breaks the example breaks this build, and
//! an edit of either copy alone fails the test.
//!
//! The example is compiled, not run here: it is the pipeline of `indentify identify` on R1,
//! whose output the README pins through `crates/cli/tests/doc_samples.rs`.

#[allow(dead_code)]
mod readme_example {
    // README example begins
    use indentify_study::identify::{self, IdentifyOptions};
    use indentify_study::{ConfigSource, Error};

    fn main() -> Result<(), Error> {
        let config = ConfigSource::Path("examples/r1-maxwell.ron".into());
        let mut opts = IdentifyOptions::new(config);
        opts.out = Some("out/r1".into()); // report.md, result.json, fit.csv, figures
        opts.force = true; // replace the report of an earlier run
        let outcome = identify::run(&opts, &mut ())?;
        let (e, sd) = (outcome.value("E"), outcome.std_dev("E"));
        println!("E = {e:?} MPa, standard deviation {sd:?}");
        Ok(())
    }
    // README example ends
}

/// The lines between the markers of this file, one indentation level removed.
fn example_here() -> Vec<String> {
    let src = include_str!("readme.rs");
    let begin = src
        .find("// README example begins\n")
        .expect("begin marker");
    let begin = begin + src[begin..].find('\n').expect("line end") + 1;
    let end = begin
        + src[begin..]
            .find("    // README example ends")
            .expect("end marker");
    src[begin..end]
        .lines()
        .map(|l| l.strip_prefix("    ").unwrap_or(l).to_string())
        .collect()
}

/// The first ```rust block of the README.
fn example_in_readme() -> Vec<String> {
    let readme = include_str!("../../README.md");
    let start = readme
        .find("```rust\n")
        .expect("a ```rust block in README.md")
        + 8;
    let end = start + readme[start..].find("```").expect("the block's end");
    readme[start..end].lines().map(str::to_string).collect()
}

#[test]
fn the_readme_shows_the_compiled_example() {
    let here = example_here();
    let there = example_in_readme();
    assert!(here.len() > 5, "the example is empty: {here:?}");
    assert_eq!(
        there, here,
        "README.md's ```rust block differs from tests/tests/readme.rs's compiled copy"
    );
}
