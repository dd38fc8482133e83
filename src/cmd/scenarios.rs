//! `asi-lift scenarios`: the built-in scenarios, to list, to print and edit, to run by name.

use super::print_out;
use rig::scenario::builtin::{Builtin, BUILTINS};

/// What `asi-lift scenarios` does.
#[derive(clap::Subcommand)]
pub enum ScenariosAction {
    /// Print a built-in scenario as its TOML file, to copy and edit
    /// (`asi-lift scenarios show door > my-door.toml`).
    Show {
        /// The scenario's name, as `asi-lift scenarios` lists it.
        name: String,
    },
}

/// Lists the built-in scenarios, or prints one.
pub fn run(action: Option<ScenariosAction>) -> Result<u8, String> {
    match action {
        None => {
            let width = BUILTINS.iter().map(|b| b.name.len()).max().unwrap_or(0);
            let mut text = String::new();
            for b in BUILTINS {
                text.push_str(&format!("{:width$}  {}\n", b.name, b.summary()));
            }
            text.push_str(
                "\nasi-lift run NAME runs one; asi-lift scenarios show NAME prints it.\n",
            );
            print_out(&text)?;
        }
        Some(ScenariosAction::Show { name }) => print_out(find(&name)?.text)?,
    }
    Ok(0)
}

/// The built-in scenario `name`, or an error that lists the names.
pub fn find(name: &str) -> Result<&'static Builtin, String> {
    Builtin::find(name).ok_or_else(|| {
        let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
        format!(
            "{name}: no built-in scenario of that name; there are {}",
            names.join(", ")
        )
    })
}
