//! Plain words for the command-line slips clap can only call a conflict: two scenes in one
//! render (`raycast a.glb b.obj`), a mistyped command (`raycast chek dir`) and a command
//! after its file (`raycast Box.glb info`). clap reads the second positional word as a
//! subcommand and says "the subcommand 'b.obj' cannot be used with '<SCENE>'".

use clap::CommandFactory;

/// The commands that take files after them.
const COMMANDS: [&str; 2] = ["info", "check"];

/// What the user meant, for a clap error on the arguments `args` (without the program name);
/// `None` when the error is not one of these slips.
pub fn explain<C: CommandFactory>(error: &clap::Error, args: &[String]) -> Option<String> {
    if error.kind() != clap::error::ErrorKind::ArgumentConflict {
        return None;
    }
    let words = positional_words::<C>(args);
    let [first, second, ..] = &words[..] else {
        return None;
    };
    if COMMANDS.contains(&second.as_str()) {
        return Some(format!(
            "'{second}' goes first: raycast {second} {first} (the command comes before its files)"
        ));
    }
    if let Some(command) = COMMANDS.iter().find(|c| near(first, c)) {
        return Some(format!(
            "'{first}' is no command; did you mean 'raycast {command} {second}'?"
        ));
    }
    Some(format!(
        "one scene per render: got '{first}' and '{second}' (render them one at a time, or \
         use 'raycast info' or 'raycast check', which take several files)"
    ))
}

/// The words of `args` that are no option and no option's value.
fn positional_words<C: CommandFactory>(args: &[String]) -> Vec<String> {
    let command = C::command();
    let takes_value = |flag: &str| {
        command.get_arguments().any(|a| {
            a.get_action().takes_values()
                && (flag
                    .strip_prefix("--")
                    .is_some_and(|l| a.get_long() == Some(l))
                    || flag
                        .strip_prefix('-')
                        .and_then(|s| s.chars().next())
                        .is_some_and(|s| flag.len() == 2 && a.get_short() == Some(s)))
        })
    };
    let mut words = Vec::new();
    let mut skip_next = false;
    for arg in args {
        if std::mem::take(&mut skip_next) {
            continue;
        }
        if arg.starts_with('-') && arg.len() > 1 {
            skip_next = !arg.contains('=') && takes_value(arg);
        } else {
            words.push(arg.clone());
        }
    }
    words
}

/// Whether `word` is one or two edits (insert, delete, replace, swap) from `command`.
fn near(word: &str, command: &str) -> bool {
    let (a, b): (Vec<char>, Vec<char>) = (word.chars().collect(), command.chars().collect());
    if a == b || a.len().abs_diff(b.len()) > 2 {
        return false;
    }
    // optimal string alignment distance
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    d[0] = (0..=b.len()).collect();
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            d[i][j] = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d[i][j] = d[i][j].min(d[i - 2][j - 2] + 1);
            }
        }
    }
    d[a.len()][b.len()] <= 2
}

#[cfg(test)]
mod tests {
    use super::near;

    #[test]
    fn near_counts_edits() {
        assert!(near("chek", "check") && near("cehck", "check") && near("inof", "info"));
        assert!(near("checks", "check") && near("nfo", "info"));
        assert!(!near("check", "check") && !near("box.glb", "check") && !near("dir", "info"));
    }
}
