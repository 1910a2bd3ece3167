//! The memory a scene may take while it loads: what the loader compares with a limit before
//! each large allocation (a texture's texels, a glTF buffer, the geometry and its BVH), so that
//! a scene that cannot fit is refused before the allocation rather than aborting in it.

use bdpm_core::human_bytes;

/// A limit on the memory of the process, and the words a refusal says about it. The words are
/// the caller's: the loader does not know where a limit came from (a command line names its
/// own option, a library its own parameter).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryLimit {
    /// The limit, bytes.
    pub bytes: u64,
    /// Where it came from, as a refusal names it: `more than the {source} of 1.0 GiB`
    /// (`"available memory"`, `"memory limit"`).
    pub source: String,
    /// What to do when the machine has more memory than the limit, ending a refusal after a
    /// `; ` (`"raise the limit if the machine has it"`); `None`: nothing.
    pub remedy: Option<String>,
}

/// The loader's running account: the bytes it keeps so far (decoded texels and glTF buffers
/// held until their file is read), compared with the limit before each allocation.
#[derive(Debug, Default)]
pub(crate) struct Budget {
    limit: Option<MemoryLimit>,
    /// Decoded texels kept for the scene, bytes.
    textures: u64,
}

impl Budget {
    pub(crate) fn new(limit: Option<MemoryLimit>) -> Budget {
        Budget { limit, textures: 0 }
    }

    /// Texels kept so far, bytes.
    pub(crate) fn textures(&self) -> u64 {
        self.textures
    }

    /// Counts `bytes` of decoded texels as kept.
    pub(crate) fn keep_texels(&mut self, bytes: u64) {
        self.textures += bytes;
    }

    /// `Ok` if `bytes` more, beside what is already held (`held`, which the caller knows
    /// best), stay within the limit; otherwise the end of a message: `needs about 1.0 GiB
    /// (… ), more than the memory limit of 200.0 MiB`, with `what` in the parentheses and the
    /// limit's [`MemoryLimit::remedy`] after it.
    pub(crate) fn check(&self, held: u64, bytes: u64, what: &str) -> Result<(), String> {
        let Some(limit) = &self.limit else {
            return Ok(());
        };
        let total = held.saturating_add(bytes);
        if total <= limit.bytes {
            return Ok(());
        }
        // What is held is named only where it matters to the sum.
        let held_text = if held >= 1 << 20 {
            format!(", beside {} held already", human_bytes(held))
        } else {
            String::new()
        };
        let remedy = limit
            .remedy
            .as_ref()
            .map_or_else(String::new, |r| format!("; {r}"));
        Err(format!(
            "needs about {} ({what}{held_text}), more than the {} of {}{remedy}",
            human_bytes(bytes),
            limit.source,
            human_bytes(limit.bytes)
        ))
    }
}
