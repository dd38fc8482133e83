//! `asi-lift completions SHELL`: the shell's completion script, generated from the command's
//! own definition (clap_complete), so that it always knows every subcommand and option.

use super::print_out;
use clap_complete::Shell;

/// Arguments of `asi-lift completions`.
#[derive(clap::Args)]
pub struct CompletionsArgs {
    /// The shell to complete in; clap refuses any other by name and lists these.
    #[arg(value_enum)]
    pub shell: Shell,
}

/// Prints the completion script of `args.shell` for `cmd` (the whole `asi-lift` command).
pub fn run(args: CompletionsArgs, mut cmd: clap::Command) -> Result<u8, String> {
    let mut script = Vec::new();
    let name = cmd.get_name().to_owned();
    clap_complete::generate(args.shell, &mut cmd, &name, &mut script);
    // The generators write only ASCII and the command's own (UTF-8) help texts.
    let mut text = String::from_utf8(script).map_err(|e| format!("completion script: {e}"))?;
    if args.shell == Shell::Bash {
        text = bash_states_agreed(&text, &name);
    }
    print_out(&text)?;
    Ok(0)
}

/// clap_complete's bash script for a command whose name has a hyphen spells a subcommand's
/// state one way where it sets it (`asi__lift__subcmd__run`) and another where it reads it
/// (`asi__subcmd__lift__subcmd__run`), so nothing after a subcommand would complete (an open
/// bug of clap_complete 4.6). The readers are spelled as the setter spells them; once the
/// generator agrees with itself this changes nothing.
fn bash_states_agreed(script: &str, name: &str) -> String {
    const SEP: &str = "__subcmd__";
    if !name.contains('-') {
        return script.to_owned();
    }
    let wrong = format!("{}{SEP}", name.replace('-', SEP));
    let right = format!("{}{SEP}", name.replace('-', "__"));
    script.replace(&wrong, &right)
}
