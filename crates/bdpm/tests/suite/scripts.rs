//! Tests of the shell scripts under scripts/ with stand-ins for what they call: a fake
//! `sbatch` that runs each job at once on this machine (the array's tasks in turn, with
//! `SLURM_ARRAY_TASK_ID` set, through `sh -c` as Slurm's `--wrap` does), and a fake `bdpm`
//! for `bit-check.sh render`, which only creates the file named by `-o`.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("repository root")
}

fn text(out: &Output) -> String {
    format!(
        "status {:?}\nstdout: {}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn executable(path: &Path, body: &str) {
    std::fs::write(path, body).expect("write script");
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).expect("chmod");
}

/// A directory holding the fake `sbatch`, to put first on PATH.
fn fake_sbatch(dir: &Path) -> PathBuf {
    let bin = dir.join("fakebin");
    std::fs::create_dir_all(&bin).expect("mkdir");
    executable(
        &bin.join("sbatch"),
        r#"#!/bin/sh
array=""; wrap=""
while [ $# -gt 0 ]; do
    case "$1" in
        --array=*) array=${1#--array=} ;;
        --wrap) wrap=$2; shift ;;
    esac
    shift
done
if [ -n "$array" ]; then
    i=${array%-*}
    while [ "$i" -le "${array#*-}" ]; do
        SLURM_ARRAY_TASK_ID=$i sh -c "$wrap" >&2 || exit 1
        i=$((i + 1))
    done
else
    sh -c "$wrap" >&2 || exit 1
fi
echo "$$"
"#,
    );
    bin
}

/// Runs scripts/slurm-render.sh with the fake sbatch first on PATH, from `cwd`.
fn slurm_render(cwd: &Path, fakebin: &Path, args: &[&str]) -> Output {
    let path = format!(
        "{}:{}",
        fakebin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new(repo().join("scripts/slurm-render.sh"))
        .args(args)
        .current_dir(cwd)
        .env("PATH", path)
        .env("BDPM", env!("CARGO_BIN_EXE_bdpm"))
        .output()
        .expect("run slurm-render.sh")
}

const FLAGS: [&str; 8] = [
    "--resolution",
    "8x8",
    "--photons",
    "500",
    "--spp",
    "1",
    "--mode",
    "optimal",
];

#[test]
fn slurm_render_quotes_and_validates_its_arguments() {
    let tmp = crate::temp_dir("slurm");
    let dir = tmp.path();
    let fakebin = fake_sbatch(dir);
    // A scene and an output folder whose names hold a quote and a space.
    let odd = dir.join("it's here");
    std::fs::create_dir_all(&odd).expect("mkdir");
    let scene = odd.join("scene's.toml");
    std::fs::copy(repo().join("scenes/cornell-lambert.toml"), &scene).expect("copy scene");
    let out = odd.join("out dir");
    let mut args = vec![scene.to_str().unwrap(), "2", "2", out.to_str().unwrap()];
    args.extend(FLAGS);
    args.push("--threads=1");
    let run = slurm_render(dir, &fakebin, &args);
    assert!(run.status.success(), "{}", text(&run));
    let merged = out.join("merged.exr");
    assert!(merged.is_file(), "{}", text(&run));
    let single = dir.join("single.exr");
    let status = Command::new(env!("CARGO_BIN_EXE_bdpm"))
        .arg("render")
        .arg(&scene)
        .args(FLAGS)
        .args(["--passes", "4", "--quiet", "-o"])
        .arg(&single)
        .output()
        .expect("render");
    assert!(status.status.success(), "{}", text(&status));
    let cmp = Command::new(env!("CARGO_BIN_EXE_bdpm"))
        .args(["compare", "--require-identical"])
        .arg(&single)
        .arg(&merged)
        .output()
        .expect("compare");
    assert!(cmp.status.success(), "{}", text(&cmp));

    // Counts that are not whole numbers ≥ 1 are refused before anything is submitted, and a
    // command substitution in one is never run.
    let pwned = dir.join("PWNED");
    let hostile = format!("1$(touch '{}')", pwned.display());
    let cases = [
        ("2", hostile.as_str(), "whole number"),
        ("0", "2", "whole number"),
        ("x", "2", "whole number"),
        ("2", "-1", "whole number"),
        ("08", "2", "whole number"),
        ("65536", "65537", "exceeds 4294967296"),
    ];
    for (tasks, per, needle) in cases {
        let fresh = dir.join(format!("fresh-{tasks}"));
        let run = slurm_render(
            dir,
            &fakebin,
            &[scene.to_str().unwrap(), tasks, per, fresh.to_str().unwrap()],
        );
        assert!(!run.status.success(), "{tasks} {per}: {}", text(&run));
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(needle), "{tasks} {per}: {err}");
        assert!(!pwned.exists(), "the pass count's $(…) ran");
        assert!(!fresh.join("merged.exr").exists());
    }

    // The folder now holds two parts and a merge: a second run there (with fewer tasks, whose
    // merge would have picked up an old part) is refused and the old files are untouched.
    let before = std::fs::read(&merged).expect("read merged");
    let mut args = vec![scene.to_str().unwrap(), "1", "2", out.to_str().unwrap()];
    args.extend(FLAGS);
    let run = slurm_render(dir, &fakebin, &args);
    assert!(!run.status.success(), "{}", text(&run));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("earlier run"), "{err}");
    assert_eq!(std::fs::read(&merged).expect("read merged"), before);
}

#[test]
fn bit_check_writes_relative_folders_under_the_callers_directory() {
    let tmp = crate::temp_dir("bitcheck");
    let dir = tmp.path();
    let fake = dir.join("fake-bdpm");
    // Lists two modes, as `bdpm modes` does, and creates the file after -o, as a render would.
    executable(
        &fake,
        "#!/bin/sh\n[ \"$1\" = modes ] && { echo path; echo optimal; exit 0; }\n\
         while [ $# -gt 0 ]; do [ \"$1\" = -o ] && : > \"$2\"; shift; done\n",
    );
    let name = format!("bit-check-rel-{}", std::process::id());
    let run = Command::new(repo().join("scripts/bit-check.sh"))
        .args(["render", &name])
        .current_dir(dir)
        .env("BDPM", "./fake-bdpm")
        .output()
        .expect("run bit-check.sh");
    let in_repo = repo().join(&name);
    let polluted = in_repo.exists();
    let _ = std::fs::remove_dir_all(&in_repo);
    assert!(run.status.success(), "{}", text(&run));
    assert!(!polluted, "bit-check.sh wrote into the checkout");
    let written = std::fs::read_dir(dir.join(&name))
        .expect("the folder under the caller's directory")
        .count();
    // Both scenes in each mode the binary listed.
    assert_eq!(written, 4, "{}", text(&run));
}
