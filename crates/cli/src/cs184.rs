//! The `cs184` command: the UC Berkeley CS184 pathtracer's command line
//! (`-t 8 -s 64 -l 16 -m 5 -f out.png scene.dae`), mapped onto our renderer. Issue 6.

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
