//! The `cachert` command: parses flags, calls the library, prints errors and exits with status 2 on failure.

fn main() {
    println!("cachert: under construction");
}
