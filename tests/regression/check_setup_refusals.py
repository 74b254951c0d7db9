"""Scenes refused at set-up: exit status 2, one line on stderr naming the file, group, variable
and value with what is allowed, and nothing written (not even the output directory).

Each entry of CASES is (name, scene text, expected fragments); '{out}' in the scene is the
output directory, which must not exist afterwards. Entries whose refusal depends on the
machine (the memory estimate) are skipped where the machine is big enough to run them.
Usage: check_setup_refusals.py KNOTFLOW WORKDIR
"""
import os
import shutil
import subprocess
import sys

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def mem_total():
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


GiB = 1024 ** 3
CASES = [
    # (name, scene, fragments, memory the refusal needs to be certain: the machine must have less)
    ("memory_rpy", "&chain shape = 'straight', n_beads = 100000 /\n&output directory = '{out}' /\n",
     ["&chain: n_beads = 100000 needs about 261.2 GiB of memory per case",
      "&hydro model = 'rpy' 260.8 GiB; run diagnostics 237.3 MiB", "of this machine (allowed: "], 262 * GiB),
    ("memory_multipole", "&chain shape = 'straight', n_beads = 20000 /\n&hydro model = 'multipole', update = 'stage' /\n"
     "&output directory = '{out}', diagnostics = .false. /\n",
     ["&chain: n_beads = 20000 needs about 134.1 GiB", "&hydro model = 'multipole' 134.1 GiB)"], 134 * GiB),
    ("frames", "&integrator t_end = 1.0e7 /\n&output directory = '{out}', frame_interval = 1.0 /\n",
     ["&output: frame_interval = 1.0 with &integrator: t_end = 10000000.0 would write 10000001 frames",
      "allowed: at most 1000000 frames"], None),
    ("frames_small_interval", "&integrator t_end = 1000.0 /\n&output directory = '{out}', frame_interval = 1.0e-4 /\n",
     ["&output: frame_interval = 0.0001 with &integrator: t_end = 1000.0 would write 10000001 frames"], None),
    ("sweep_rounding", "&output directory = '{out}' /\n&sweep bending_a = 2.201, 2.204 /\n",
     ["&sweep: cases 1 (bending_a = 2.201) and 2 (bending_a = 2.204)", "'A2.20.h5'"], None),
    ("sweep_seed_twice", "&chain shape = 'candycane' /\n&output directory = '{out}' /\n&sweep seed = 1, 2, 1 /\n",
     ["&sweep: cases 1 (seed = 1) and 3 (seed = 1)", "'s1.h5'"], None),
]

# Coordinate files are read and checked at set-up.
for name, points, frag in [
        ("coords_one_bead", "1 2 3\n", "holds fewer than 2 beads"),
        ("coords_columns", "1 2 3\n4 5\n", "line 2: expected three numbers 'x y z', found 2 item(s) in '4 5'"),
        ("coords_nan", "1 2 3\n2 2 nan\n", "line 2: item 3 'nan' is not a number"),
        ("coords_coincident", "1 2 3\n2 2 3\n1 2 3\n", "beads 1 and 3 coincide (allowed: distinct points)"),
        # bond_length 1.02 (default): 2 x 1.02 = 2.04 is the longest bond allowed
        ("coords_stretched", "0 0 0\n0 0 1.02\n0 0 11.22\n",
         "is not allowed (bonds of at most 2.0 times bond_length = 1.02; bond 2 (beads 2 and 3) is 10.2000 long)")]:
    xyz = os.path.join(work, name + ".xyz")
    with open(xyz, "w") as f:
        f.write(points)
    CASES.append((name, "&chain shape = 'file', coordinate_file = '%s' /\n&output directory = '{out}' /\n" % xyz,
                  ["&chain: coordinate_file", frag], None))
# The models are built at set-up: what they reject is refused before any case runs.
CASES.append(("eps_lub_zero", "&hydro model = 'multipole', eps_lub = 0.0 /\n&output directory = '{out}' /\n",
              ["&hydro: eps_lub = 0.0", "(0, 0.5)"], None))
CASES.append(("orientation_long", "&chain orientation = 'bc' /\n&output directory = '{out}' /\n",
              ["&chain: orientation = 'bc' is 2 characters long (allowed: at most 1)"], None))
CASES.append(("twice", "&integrator t_end = 10.0, t_end = 20.0 /\n&output directory = '{out}' /\n",
              ["&integrator: t_end is given twice"], None))
CASES.append(("outside", "&output directory = '{out}' /\nt_end = 5\n",
              ["text outside a group: \"t_end = 5\""], None))

total = mem_total()
ran = skipped = 0
for name, text, fragments, needs in CASES:
    if needs is not None and (total is None or total >= needs):
        skipped += 1
        print("skipped %s: this machine has enough memory to run it" % name)
        continue
    out = os.path.join(work, name + "_out")
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text.format(out=out))
    r = subprocess.run([exe, path], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, (name, r.returncode, r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, (name, r.stderr)
    assert lines[0].startswith("knotflow: error: " + path + ": "), (name, lines[0])
    for frag in fragments:
        assert frag in lines[0], (name, frag, lines[0])
    assert not os.path.exists(out), name + ": a refused scene created its output directory"
    ran += 1
# The bad-scene corpus: one scene per rule of the reader and the validation, each with the exact
# message that must follow "knotflow: error: <file>: " (run in a scratch directory: the default
# output directory ./results must not appear).
#: The case-name rule in the words of the refusal (kf_scene_output: case_name_allowed).
CASE_NAME_ALLOWED = ("letters, digits and _ . - + only, starting with a letter, a digit or _, at most 100 characters")
CORPUS = [
    ('unknown_group',
     "&chains shape = 'trefoil' /",
     'unknown group &chains (allowed: &chain, &forces, &flow, &hydro, &integrator, &output, &sweep)'),
    ('unknown_variable',
     "&chain shapes = 'trefoil' /",
     "&chain: unknown variable 'shapes' (allowed: shape, n_beads, orientation, trefoil_removed_point, bond_length, coordinate_file, seed, straight_direction, candycane_rotation, tilt_deg, perturbation, stepper_state)"),
    ('wrong_type_real',
     "&forces spring_k = 'stiff' /",
     "&forces: spring_k = 'stiff' is not valid (expected a real number)"),
    ('wrong_type_logical',
     '&forces springs = maybe /',
     '&forces: springs = maybe is not valid (expected .true. or .false.)'),
    ('n_beads_one',
     "&chain shape = 'straight', n_beads = 1 /",
     '&chain: n_beads = 1 is not allowed (an integer >= 2)'),
    ('n_beads_huge',
     "&chain shape = 'random', n_beads = 200000 /",
     '&chain: n_beads = 200000 is not allowed (at most 100000)'),
    ('orientation_z',
     "&chain orientation = 'z' /",
     "&chain: orientation = 'z' is not allowed (one of a, b, c, d, e)"),
    ('removed_point',
     '&chain trefoil_removed_point = 0 /',
     '&chain: trefoil_removed_point = 0 is not allowed (an integer from 1 to 100)'),
    ('bond_length_neg',
     '&chain bond_length = -1.0 /',
     '&chain: bond_length = -1.0 is not allowed (a number in (0, 100))'),
    ('coord_missing',
     "&chain shape = 'file', coordinate_file = '/nonexistent/x.xyz' /",
     "&chain: coordinate_file = '/nonexistent/x.xyz' is not allowed (an existing file (not found))"),
    ('coord_empty_name',
     "&chain shape = 'file' /",
     "&chain: coordinate_file = '' is not allowed (a file name (required with shape = 'file'))"),
    ('candycane_rotation_bad',
     "&chain shape = 'candycane', candycane_rotation = 'tilt_y' /",
     "&chain: candycane_rotation = 'tilt_y' is not allowed (one of random, tilt_x)"),
    ('tilt_without_tilt_x',
     "&chain shape = 'candycane', tilt_deg = 30 /",
     "&chain: tilt_deg = 30.0 is not allowed (0 unless candycane_rotation = 'tilt_x')"),
    ('tilt_range',
     "&chain shape = 'candycane', candycane_rotation = 'tilt_x', tilt_deg = 400 /",
     "&chain: tilt_deg = 400.0 is not allowed (a number of degrees from -360.0 to 360.0)"),
    ('perturbation_negative',
     '&chain perturbation = -1e-6 /',
     '&chain: perturbation = -0.1E-5 is not allowed (a length in d from 0 to 0.1)'),
    ('direction_zero',
     "&chain shape = 'straight', straight_direction = 0, 0, 0 /",
     '&chain: straight_direction = 0.0, 0.0, 0.0 is not allowed (a non-zero vector)'),
    ('spring_k_nan',
     '&forces spring_k = nan /',
     '&forces: spring_k = NaN is not allowed (a finite number)'),
    ('bending_a_neg',
     '&forces bending_a = -1.0 /',
     '&forces: bending_a = -1.0 is not allowed (a number in [0, 1e7))'),
    ('ev_range_zero',
     '&forces ev_range = 0.0 /',
     '&forces: ev_range = 0.0 is not allowed (a number in (0, 10])'),
    ('ev_strength_inf',
     '&forces ev_strength = inf /',
     '&forces: ev_strength = Inf is not allowed (a finite number)'),
    ('external_force_inf',
     '&forces external_force = 0, inf, 0 /',
     '&forces: external_force = 0.0, Inf, 0.0 is not allowed (finite numbers)'),
    ('flow_type',
     "&flow flow_type = 'swirl' /",
     "&flow: flow_type = 'swirl' is not allowed (one of shear, linear, quiescent)"),
    ('shear_rate_inf',
     '&flow shear_rate = inf /',
     '&flow: shear_rate = Inf is not allowed (a finite number)'),
    ('gradient_trace',
     "&flow flow_type = 'linear', velocity_gradient = 1, 0, 0, 0, 0, 0, 0, 0, 0 /",
     '&flow: velocity_gradient = trace 1.0 is not allowed (a traceless matrix (incompressible flow))'),
    ('model',
     "&hydro model = 'stokesian' /",
     "&hydro: model = 'stokesian' is not allowed (one of none, rpy, multipole)"),
    ('order_9',
     "&hydro model = 'multipole', order = 9 /",
     '&hydro: order = 9 is not allowed (an integer from 1 to 8)'),
    ('order_lub_7',
     "&hydro model = 'multipole', order = 7 /",
     '&hydro: order = 7 is not allowed (at most 6 with lubrication = .true. (tables exist for L = 1..6))'),
    ('eps_lub_big',
     '&hydro eps_lub = 0.5 /',
     '&hydro: eps_lub = 0.5 is not allowed (a number in (0, 0.5), or negative for the integration tolerance)'),
    ('update',
     "&hydro update = 'sometimes' /",
     "&hydro: update = 'sometimes' is not allowed (one of stage, adaptive, iterative)"),
    ('method',
     "&integrator method = 'euler' /",
     "&integrator: method = 'euler' is not allowed (one of dopri45, rk4, ros34pw2, ros34pw3)"),
    ('t_end_zero',
     '&integrator t_end = 0.0 /',
     '&integrator: t_end = 0.0 is not allowed (a number > 0)'),
    ('tolerance_one',
     '&integrator tolerance = 1.0 /',
     '&integrator: tolerance = 1.0 is not allowed (a number in (0, 1))'),
    ('dt_min_zero',
     '&integrator dt_min = 0.0 /',
     '&integrator: dt_min = 0.0 is not allowed (a number > 0)'),
    ('dt_max_small',
     '&integrator dt_min = 1e-3, dt_max = 1e-4 /',
     '&integrator: dt_max = 0.0001 is not allowed (a number > dt_min = 0.001)'),
    ('dt_initial_out',
     '&integrator dt_initial = 10.0 /',
     '&integrator: dt_initial = 10.0 is not allowed (a number in [dt_min, dt_max] = [0.1E-8, 0.5])'),
    ('max_steps_zero',
     '&integrator max_steps = 0 /',
     '&integrator: max_steps = 0 is not allowed (an integer >= 1)'),
    ('directory_empty',
     "&output directory = '' /",
     "&output: directory = '' is not allowed (a directory name)"),
    ('frame_interval_zero',
     '&output frame_interval = 0.0 /',
     '&output: frame_interval = 0.0 is not allowed (a number > 0)'),
    ('progress_neg',
     '&output progress_interval = -1.0 /',
     '&output: progress_interval = -1.0 is not allowed (a number >= 0 (seconds; 0 = every frame))'),
    ('case_name_slash',
     "&output case_name = 'a/b' /",
     "&output: case_name = 'a/b' is not allowed (%s)" % CASE_NAME_ALLOWED),
    # names that are paths or hidden files (issue 37: '.hidden' was accepted and then left out
    # by knotflow-report, '..' wrote '...h5'), option-like names, and names too long for the
    # files named after them (a 240-character name passed --dry-run, computed the case and
    # failed writing the summary)
    ('case_name_hidden',
     "&output case_name = '.hidden' /",
     "&output: case_name = '.hidden' is not allowed (%s)" % CASE_NAME_ALLOWED),
    ('case_name_dotdot',
     "&output case_name = '..' /",
     "&output: case_name = '..' is not allowed (%s)" % CASE_NAME_ALLOWED),
    ('case_name_option',
     "&output case_name = '-rf' /",
     "&output: case_name = '-rf' is not allowed (%s)" % CASE_NAME_ALLOWED),
    ('case_name_240',
     "&output case_name = '%s' /" % ("n" * 240),
     "&output: case_name = '%s' is not allowed (%s)" % ("n" * 240, CASE_NAME_ALLOWED)),
    ('case_name_sweep_too_long',
     "&output case_name = '%s' /\n&sweep bending_a = 1.0 /" % ("n" * 95),
     "&output: case_name = '%s_A1.00' is not allowed (%s) [in &sweep case %s_A1.00]"
     % ("n" * 95, CASE_NAME_ALLOWED, "n" * 95)),
    ('group_twice',
     "&chain shape = 'trefoil' / &chain orientation = 'b' /",
     'group &chain appears twice'),
    ('unclosed',
     "&chain shape = 'trefoil'",
     'group starting at "&chain shape = \'trefoil\'" has no closing "/"'),
    ('no_group_name',
     "& shape = 'trefoil' /",
     '"&" not followed by a group name near " shape = \'trefoil\'"'),
    ('sweep_combine',
     "&sweep combine = 'cross', bending_a = 1, 2 /",
     "&sweep: combine = 'cross' is unknown (allowed: product, zip)"),
    ('sweep_unknown',
     '&sweep bending = 1, 2 /',
     "&sweep: unknown variable 'bending' (allowed: bending_a, orientation, seed, combine)"),
    ('sweep_zip_lengths',
     "&sweep combine = 'zip', bending_a = 1, 2, 3, seed = 1, 2 /",
     "&sweep: combine = 'zip' needs lists of equal length, but bending_a has 3 values, orientation 0 and seed 2 (empty lists are allowed)"),
    ('sweep_orientation_straight',
     "&chain shape = 'straight' / &sweep orientation = 'a', 'b' /",
     "&sweep: orientation is listed but &chain: shape = 'straight' has no orientations (only trefoil has a-e)"),
    ('sweep_bad_value',
     '&sweep bending_a = 1, x /',
     '&sweep: bending_a = 1, x is not valid (expected a list of values, at most 256)'),
    ('sweep_orientation_z',
     "&sweep orientation = 'a', 'z' /",
     "&chain: orientation = 'z' is not allowed (one of a, b, c, d, e) [in &sweep case orz]"),
    ('sweep_a_negative',
     '&sweep bending_a = 1.0, -2.0 /',
     '&forces: bending_a = -2.0 is not allowed (a number in [0, 1e7)) [in &sweep case A-2.00]'),
    ('stresslet_quiescent',
     "&flow flow_type = 'quiescent' /\n&output stresslet = .true. /",
     "&output: stresslet = .true. is not allowed (.false. unless &flow flow_type = 'shear' with shear_rate /= 0 "
     "(the viscosity and normal-stress coefficients are those of simple shear))"),
    ('stresslet_order_one',
     "&hydro model = 'multipole', order = 1 /\n&output stresslet = .true. /",
     "&output: stresslet = .true. is not allowed (.false. with &hydro model = 'multipole' and order = 1 "
     "(L = 1 has no stresslet moments; use order >= 2))"),
]
corpus_dir = os.path.join(work, "corpus")
os.makedirs(os.path.join(corpus_dir, "run"))
for name, text, message in CORPUS:
    path = os.path.join(corpus_dir, name + ".nml")
    with open(path, "w") as f:
        f.write(text + "\n")
    # a dry run refuses what the run refuses
    for extra in ([], ["--dry-run"]) if name.startswith("case_name") else ([],):
        r = subprocess.run([exe, path] + extra, capture_output=True, text=True, timeout=120,
                           cwd=os.path.join(corpus_dir, "run"))
        assert r.returncode == 2, (name, extra, r.returncode, r.stdout, r.stderr)
        assert r.stderr.strip() == "knotflow: error: " + path + ": " + message, (name, r.stderr, message)
        assert os.listdir(os.path.join(corpus_dir, "run")) == [], (name, "wrote something")
    ran += 1

# Not a scene at all: a directory, a binary file, an empty file (the output directory would be
# ./results: run in a scratch directory and check that nothing appears there).
scratch = os.path.join(work, "scratch")
os.makedirs(scratch)
binary = os.path.join(work, "binary.nml")
with open(binary, "wb") as f:
    f.write(bytes(range(256)) * 8)
empty = os.path.join(work, "empty.nml")
open(empty, "w").close()
for path, frag in [(work, "is a directory"), (binary, "not a text file"),
                   (empty, "no namelist group found")]:
    r = subprocess.run([exe, path], capture_output=True, text=True, timeout=120, cwd=scratch)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and frag in lines[0], (path, r.returncode, r.stderr)
    assert lines[0].startswith("knotflow: error: " + path + ": "), lines[0]
    assert os.listdir(scratch) == [], os.listdir(scratch)
    ran += 1

# A dry run writes nothing, not even the output directory: a valid scene whose directory does
# not exist yet is listed and the directory stays absent (--write-scenes writes only the scenes
# asked for); a directory that could not be made (below a regular file) is refused all the same.
dry = os.path.join(work, "dry")
os.makedirs(dry)
valid = os.path.join(dry, "valid.nml")
out = os.path.join(dry, "deep", "out")
with open(valid, "w") as f:
    f.write("&output directory = '%s' /\n&sweep bending_a = 1.0, 2.0 /\n" % out)
for extra in (["--dry-run"], ["--write-scenes", os.path.join(dry, "scenes")]):
    r = subprocess.run([exe, valid] + extra, capture_output=True, text=True, timeout=120, cwd=dry)
    assert r.returncode == 0, (extra, r.returncode, r.stderr)
    assert "2 case(s) from " + valid in r.stdout and "output in " + out in r.stdout, r.stdout
    assert not os.path.exists(os.path.dirname(out)), (extra, "a dry run created the output directory")
    ran += 1
assert sorted(os.listdir(os.path.join(dry, "scenes"))) == ["A1.00.nml", "A2.00.nml"], os.listdir(dry)
blocker = os.path.join(dry, "plain_file")
open(blocker, "w").close()
for name, directory, message in [
        ("dry_below_file", os.path.join(blocker, "out"),
         "cannot create directory '%s': '%s' is not a directory" % (os.path.join(blocker, "out"), blocker)),
        ("dry_is_file", blocker, "'%s' is not a directory" % blocker)]:
    path = os.path.join(dry, name + ".nml")
    with open(path, "w") as f:
        f.write("&output directory = '%s' /\n" % directory)
    r = subprocess.run([exe, path, "--dry-run"], capture_output=True, text=True, timeout=120, cwd=dry)
    assert r.returncode == 2, (name, r.returncode, r.stdout, r.stderr)
    assert r.stderr.strip() == "knotflow: error: %s: &output: directory = '%s': %s" % (path, directory, message), \
        (name, r.stderr)
    ran += 1
print("set-up refusals and dry runs: %d as expected, %d skipped" % (ran, skipped))
