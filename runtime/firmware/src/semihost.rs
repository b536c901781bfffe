//! Host I/O over semihosting beyond `hprintln!`: the command line and a binary output file.

use cortex_m_semihosting::{nr, syscall, syscall1};

/// The semihosting command line (`-semihosting-config …,arg=…`), in `buf`.
pub fn command_line(buf: &mut [u8]) -> &str {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: GET_CMDLINE writes at most `buf.len()` bytes into `buf` and the length into the
    // block; both outlive the call.
    let r = unsafe { syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    // SAFETY: the host wrote the block during the call above.
    let len = unsafe { core::ptr::read_volatile(&block[1]) };
    if r != 0 || len > buf.len() {
        return "";
    }
    core::str::from_utf8(&buf[..len]).unwrap_or("")
}

/// The value after `--name` on the command line.
pub fn option<'a>(cmdline: &'a str, name: &str) -> Option<&'a str> {
    let mut words = cmdline.split_ascii_whitespace();
    words.find(|w| w.strip_prefix("--") == Some(name))?;
    words.next()
}

/// True if `--name` is on the command line.
pub fn flag(cmdline: &str, name: &str) -> bool {
    cmdline
        .split_ascii_whitespace()
        .any(|w| w.strip_prefix("--") == Some(name))
}

/// A file on the host, opened for writing (truncated), binary.
pub struct HostFile {
    fd: usize,
}

impl HostFile {
    /// Opens `path` (at most 255 bytes) for writing.
    pub fn create(path: &str) -> Option<HostFile> {
        let mut name = [0u8; 256];
        let n = path.len();
        if n >= name.len() {
            return None;
        }
        name[..n].copy_from_slice(path.as_bytes());
        // SAFETY: OPEN reads the NUL-terminated name of length n.
        let fd = unsafe { syscall!(OPEN, name.as_ptr(), nr::open::W_TRUNC_BINARY, n) };
        (fd as isize != -1).then_some(HostFile { fd })
    }

    /// Writes all of `bytes`; false on a host error.
    pub fn write_all(&mut self, bytes: &[u8]) -> bool {
        // SAFETY: WRITE reads `bytes` during the call; it returns the bytes not written.
        let left = unsafe { syscall!(WRITE, self.fd, bytes.as_ptr(), bytes.len()) };
        left == 0
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: closes the descriptor this value owns.
        unsafe { syscall!(CLOSE, self.fd) };
    }
}
