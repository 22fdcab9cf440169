//! Library errors name options by meaning ("the texture memory limit", "the pixel error"): only
//! the command line knows how each is spelt. Before an error is printed, every option it names
//! is followed by its flag, so the message tells a user what to type.

/// Each phrase the libraries use for an option the command line sets, and that option's flag.
const OPTION_FLAGS: &[(&str, &str)] = &[
    ("raise the input size limit", "--max-input-size"),
    ("raise the texture memory limit", "--max-texture-memory"),
    ("raise the vertex limit", "--max-vertices"),
    ("raise the animation key limit", "--max-animation-keys"),
    ("the pixel error", "--pixel-error"),
    ("the number of ε steps", "--steps"),
    ("the number of seeds", "--seeds"),
    ("the screen height must", "--screen-height"),
];

/// `message` with the flag in parentheses after each option it names.
pub fn with_flags(message: &str) -> String {
    let mut out = message.to_string();
    for (phrase, flag) in OPTION_FLAGS {
        out = out.replace(phrase, &format!("{phrase} ({flag})"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_named_by_meaning_gets_its_flag() {
        let m = "t.glb: textures decode to 9 GB, over the texture memory limit of 384 MB \
                 (raise the texture memory limit to read it)";
        let shown = with_flags(m);
        assert!(
            shown.ends_with("(raise the texture memory limit (--max-texture-memory) to read it)")
        );
        assert_eq!(with_flags("nothing named"), "nothing named");
    }
}
