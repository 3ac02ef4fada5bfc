//! Nothing here: the programs are the examples (`cargo run --example spin`).
