//! Feature `embed`: a blob and a task block linked into the image at the BLOB and TASK
//! regions (`memory.x` places the sections), for a self-contained image that needs no
//! separate flashing. build.rs names the files (PRF_EMBED_BLOB, PRF_EMBED_TASK).

#[used]
#[unsafe(link_section = ".prf_blob")]
static BLOB: [u8; include_bytes!(env!("PRF_EMBED_BLOB")).len()] =
    *include_bytes!(env!("PRF_EMBED_BLOB"));

#[used]
#[unsafe(link_section = ".prf_task")]
static TASK: [u8; include_bytes!(env!("PRF_EMBED_TASK")).len()] =
    *include_bytes!(env!("PRF_EMBED_TASK"));
