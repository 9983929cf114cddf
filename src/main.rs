fn main() {
    println!("tactile-workbench");
}
