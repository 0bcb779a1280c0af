//! The `petrel` command line, with the built-in module types.

fn main() -> std::process::ExitCode {
    petrel::Petrel::new().main()
}
