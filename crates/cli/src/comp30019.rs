//! The `comp30019` command: the University of Melbourne COMP30019 ray tracer's command line
//! (`-f scene.txt -o out.png -x 3 ...`), mapped onto our renderer. Issue 4.

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
