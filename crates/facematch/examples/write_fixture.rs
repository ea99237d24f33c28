//! Writes the template format fixture `fixtures/facematch/small.bpt` (run from the workspace
//! root after a deliberate format change, with the format version raised).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::path::Path::new("fixtures/facematch/small.bpt");
    facematch::fixture::small_template().write(path)?;
    println!("{}", path.display());
    Ok(())
}
