//! The `curvefit` command-line tool. See `curvefit --help` and the README.

/// mimalloc, not the system allocator: a large solve's arrays are tens of megabytes, and glibc's
/// malloc maps such blocks fresh from the kernel, so every page is faulted in and zeroed on
/// first touch (~4 µs per 4 KiB page on the 2-core development VM: ~10⁴ faults for a 10⁵-point
/// interpolation); mimalloc reuses the memory a finished stage freed.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    // Solvers report failures as values; a panic would be a bug. Keep its report to one line.
    // Set CURVEFIT_DEBUG_PANICS=1 to see the standard panic report when debugging.
    if std::env::var_os("CURVEFIT_DEBUG_PANICS").is_none() {
        std::panic::set_hook(Box::new(|_| {}));
    }
    // Each worker on its own processor (`curvefit::threads`: a woken worker otherwise waited
    // behind the thread that woke it).
    curvefit::threads::install_global();
    use std::io::IsTerminal;
    let stdin = std::io::stdin();
    let code = curvefit::cli::run_with_terminals(
        std::env::args_os(),
        &mut stdin.lock(),
        curvefit::cli::Terminals {
            stdin: stdin.is_terminal(),
            stderr: std::io::stderr().is_terminal(),
        },
        &mut std::io::stdout().lock(),
        // Unlocked: each write takes the lock, so a line written to standard error from another
        // thread (a library's diagnostic) waits for one write, not for the whole run.
        &mut std::io::stderr(),
    );
    std::process::exit(code);
}
