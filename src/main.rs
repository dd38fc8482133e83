//! The `asi-lift` command.

fn main() {
    println!("asi-lift: the `run` command is not built yet; see README.md");
}
