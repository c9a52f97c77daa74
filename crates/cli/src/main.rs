//! `esrl`: train, evaluate, compare and record humanoid walking controllers.

fn main() {
    println!("esrl");
}
