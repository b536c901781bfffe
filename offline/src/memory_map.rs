//! The cell controller's memory map as `memory.x` gives it (the linker script is the one home
//! of the regions; the host tools read their sizes from it).

/// The linker script the firmware is linked with.
const MEMORY_X: &str = include_str!("../../memory.x");

/// Bytes of the flash region the blob is written to (`memory.x` BLOB): the default budget of
/// `prf learn --max-blob-bytes`, and what `prf firmware` checks a blob against.
pub fn blob_region_bytes() -> usize {
    // A test checks memory.x has the region; the script is compiled in.
    region_length(MEMORY_X, "BLOB").unwrap_or(0)
}

/// LENGTH of region `name` in the MEMORY command of a linker script (`K` and `M` suffixes).
fn region_length(script: &str, name: &str) -> Option<usize> {
    let line = script.lines().find(|l| {
        let l = l.trim_start();
        l.strip_prefix(name)
            .is_some_and(|rest| rest.trim_start().starts_with(':'))
    })?;
    let value = line
        .split("LENGTH")
        .nth(1)?
        .trim_start()
        .strip_prefix('=')?;
    let value = value.trim().trim_end_matches(',');
    let (digits, scale) = match value.as_bytes().last()? {
        b'K' => (&value[..value.len() - 1], 1 << 10),
        b'M' => (&value[..value.len() - 1], 1 << 20),
        _ => (value, 1),
    };
    let n = match digits.strip_prefix("0x") {
        Some(hex) => usize::from_str_radix(hex, 16).ok()?,
        None => digits.parse().ok()?,
    };
    n.checked_mul(scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_blob_region_is_read_from_memory_x() {
        assert_eq!(blob_region_bytes(), 960 * 1024);
        assert_eq!(region_length(MEMORY_X, "TASK"), Some(64 * 1024));
        assert_eq!(region_length(MEMORY_X, "FLASH"), Some(3 << 20));
        assert_eq!(
            region_length("  R : ORIGIN = 0, LENGTH = 0x100", "R"),
            Some(256)
        );
        assert_eq!(region_length("RAM : ORIGIN = 0, LENGTH = 4M", "BLOB"), None);
    }
}
