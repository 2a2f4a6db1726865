//! The `debug-paths` command: trace N paths through one pixel with a recorder and write their
//! segments as a PLY edge set or JSON. Issue 7.

use crate::Failure;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Arguments (not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub rest: Vec<String>,
}

pub fn run(_args: Args) -> Result<(), Failure> {
    Err(Failure::other("not implemented yet"))
}
