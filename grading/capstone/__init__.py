"""Lab 13, the capstone: each student's attitude filter scored on BROAD trials they never saw (the trusted side).

    python -m grading.capstone fetch                       # make capstone-data: the hidden trials, once
    python -m grading.capstone grade [--class NAME]        # every submitted/<student>/13_capstone/13_capstone.ipynb

The student hands in a notebook whose answer cells define ``estimate(gyr, acc, mag, fs) -> (N, 4)``: unit quaternions
``[w, x, y, z]``, body->ENU, the course's convention (:mod:`fusionlab.rotations`), from gyro (rad/s), accelerometer
(m/s^2) and magnetometer (uT) readings in the sensor frame at ``fs`` Hz. Grading happens here, not in the student's
process:

* **Sensor set.** A filter is 9D (gyro, accelerometer, magnetometer) unless its answer cells declare
  ``SENSORS = "6D"`` (:data:`fusionlab.capstone.SENSORS`). The declaration is read here, from the code
  (:func:`declared_sensors`: a top-level assignment of the literal ``"6D"`` or ``"9D"`` in a cell the box runs), never
  from the student's process; anything else that sets ``SENSORS`` makes the filter 9D, with a note that says why. A 6D
  filter is called with ``mag=None`` in every call, the causality check's too, and is scored on inclination.

* **Hidden trials.** The instructor scores on the BROAD trials that the course does not ship (:data:`HIDDEN`, 31 of
  39; ``data/broad/`` and the student release hold the other 8). ``make capstone-data`` gets them once through
  :func:`fusionlab.datasets.fetch_trial` (each file downloaded to a temporary file, checked and only then renamed
  into the cache); grading refuses to start without all of them and says how to get them (:func:`hidden_trials`).
* **What the student's code sees.** Its notebook's answer cells (and the cells they need) run in a box of the
  grading sandbox (:mod:`grading.sandbox`, :mod:`grading.box`) with no data at all: no ``data/``, no BROAD cache, no
  submission folder. The box's library holds the modules the rules allow and the notebook needs
  (:data:`fusionlab.capstone.BOX_MODULES`: rotations, metrics and what they and the lab's setup cell import); every
  other module -- the filters and data loaders (:data:`FILTER_MODULES`, :data:`FILE_MODULES`), and the building
  blocks the rules do not allow (Kalman steps, eCompass, tilt formulas: :func:`absent_modules`) -- is absent as
  code: its file is a placeholder written here (:func:`placeholder_module`) that imports, keeps the few no-ops the
  library touches as it loads (:data:`KEEP`) and refuses every other name, public or private, so no function of
  those modules, nor their source or bytecode, is in the box (:func:`box_library`). Reaching a filter or data
  module is named as a cheat; reaching a building block fails the call (:data:`BLOCK_MESSAGE`), and the student's
  own checks name it before they hand in (:func:`fusionlab.capstone.outside_box`).
  ``vqf``, ``ahrs``, ``imufusion`` and ``filterpy`` are shadowed by packages that refuse to load, and their
  installed copies are hidden (an empty folder mounted over each, :func:`grading.sandbox.package_paths`), so that
  taking the shadow off ``sys.path`` reaches nothing. The box's CPU-time limit is made from the trials' budgets
  (:func:`box_limits`).
  The judge sends each trial's sensor data (nothing else) as a call of ``estimate`` and gets the quaternions back
  as plain numbers. Ground truth, metrics and scores exist only in this process.
* **Each trial is disguised, and no honest score moves.** Before a class is graded every trial loses a secret number
  of samples at its start (under 0.5 s) and at its end (under 3 s, none of the movement phase), so that its length
  does not name it, and gets fresh white noise of about the sensors' own (:data:`DISGUISE_NOISE`), so that no raw
  sample of the published trial is found again. The sensor frame is not turned: a turn changes the score of a
  filter that is not rotation-equivariant (Madgwick's, whose gradient step depends on the axes), so honest filters
  would be scored with luck (:func:`disguise` states the measured effects).
* **Plausibility.** A submission could still recognise a trial (from its movement, say) and return its published
  reference: an error far below any filter's. A scored RMSE below :data:`IMPLAUSIBLE` x the best reference
  filter's on at least two trials (and a tenth of those that ran, :data:`IMPLAUSIBLE_TRIALS`) is named (``detects
  the trial``: "implausibly close to the optical reference ... review the code") and gets no points for the filter;
  the instructor who has read the code and trusts it grades again with ``--cleared <student>``
  (:func:`implausibly_close`).
* **Scores.** The dataset authors' metrics (:func:`fusionlab.metrics.broad_rmse`: total, heading and inclination
  RMSE in degrees over the movement phase), per trial and as their mean, as :mod:`fusionlab.bench` computes them;
  the run time of each call, against a time budget per trial (:func:`fusionlab.capstone.budget_seconds`). A filter
  is scored on one of them, its sensor set's: total RMSE (9D) or inclination RMSE (6D, which cannot know heading).
  A trial without a valid estimate (an error, over its budget, not N unit quaternions) counts with that RMSE of an
  estimate that never moves (the identity quaternion).
* **Causality** (as ``tests/test_causality.py`` checks the library): on one trial, chosen in secret, every sample
  after k is replaced (sample k held, with noise) and ``estimate`` is called again; its output up to k must not change
  (1e-10), for three k drawn in secret (:func:`fusionlab.capstone.causal_ks` with the grader's generator: in the first
  hundredth, the first tenth and the second half of the trial); every other trial is checked so at one secret k. On
  every trial ``estimate`` is also called on the samples up to each of four secret cuts alone (:func:`prefix_cuts`,
  the last past 95 % of the trial): its output must be the first rows of its output on the whole trial. Each of these
  calls runs in a box started for it alone (:meth:`Runner.call_fresh`), all of them before any box sees a whole trial
  (the kernel's file caches forgotten before them and in between, :meth:`Runner.forget`, as root) and, on each
  trial, in the order of how far into it their data reach (:func:`plan`): what a box could pass to a later one holds
  nothing of the samples the later call was not given (:mod:`grading.capstone.causality`). One more prefix call, at a
  secret cut past all of theirs, comes after the whole trial's (:func:`final_cut`): a filter that learned where they
  stopped, and looked ahead only past it, is caught there. A filter that ran on the trials but not on the check's data
  (an error, over its budget) was never shown causal and gets no points for the filter (:func:`gates_failed`): else
  failing the check's calls would escape it.
* **The code** the box runs is read first, as the box's IPython shell runs it (:func:`scan`, :func:`as_run`,
  :func:`library_copies`): imports or uses of a reference filter, files read, the import system reached around
  (:func:`grading.codescan.tampering`, with the indirect loaders that the table of exercises lists for the
  capstone's filter -- ``importlib``, ``runpy``, ``pkgutil.resolve_name``, ``pydoc``, ``timeit``, ``ctypes`` ...,
  :func:`loaders` -- and ``get_ipython``), and a library filter pasted in (:mod:`grading.similarity`'s fingerprints
  against the library's filter modules; the rotation and metric helpers that the rules allow are not looked for).
  Names written in the code only: what is built at run time is not seen, and no list of loaders is complete. The
  scan names what is written; the box is the defence: it holds nothing those names would reach.
* **Feedback on hidden trials** holds no text of the student's code: what a call of ``estimate`` raised or returned
  is reported in words written here (the type of a built-in error, what was wrong with the output, the placeholder
  or refusing package it reached: :func:`error_message`, :func:`invalid_message`), never its message, which could
  carry the trial's numbers. Of the notebook's cells, the feedback names those that failed in the first box, which
  runs them before any trial is sent, never with their text (:class:`Runner`); in a box started after a trial was
  sent, which cells fail is not reported at all.
* **Points** come from the stated rubric (:data:`RUBRIC`), not from rank: 2 for a valid estimate on every trial
  within its budget, and up to 8 that grow with the mean RMSE the filter is scored on, on a log scale from
  Madgwick's filter's mean to VQF's with the same sensors (9D: total RMSE of the 9D versions; 6D: inclination RMSE of
  the 6D versions; :func:`fusionlab.capstone.accuracy_points`), both computed here on the same trials as the
  student's. A non-causal submission, one whose causality was never shown, or one named in :data:`CHEATS`, gets no
  points for the filter.
* **Reference rows** (:func:`references`), for each sensor set on the same trials: VQF (default parameters), Madgwick
  (``ahrs``, its default gain) and the library's best filter of that set (by the RMSE the set is scored on). They are
  scored like a student of their set and listed on the leaderboard; the output of every reference filter that ran,
  either set, is what the match check compares a student's with, and their RMSEs set the plausibility gate's bar.
  They are computed once per disguise and kept in
  ``<out>/references.npz`` (:func:`cached_references`), keyed by the seed, the trials (names, lengths, a hash of
  their disguised data) and a hash of the code (the library's source files, ``scoring.py``, the versions of vqf and
  ahrs): re-grading one student with the class's seed reuses them (Madgwick's filter alone takes seconds per
  trial); any difference computes them again.
* **Seed.** ``--seed`` sets the disguise's secret; without it the seed that ``<out>/run.json`` saved for the same
  trials is used again (one disguise per class), else a new random one (``--new-seed`` forces a new one).

Outputs (``--out``, default ``capstone_<class>/`` in the course): ``leaderboard.html`` and ``leaderboard.csv`` (one
row per student and per reference: sensor set, mean total / heading / inclination RMSE, rank, ratio to VQF with the
same sensors, run time (in the CSV only: a filter's own timing can spell a hidden figure), budget and causality held,
points, cheats; 9D and 6D filters are ranked separately, each rank
within its set, a table per set on the page), ``trials.csv`` (every student and reference on every trial), per
student ``feedback/<student>/capstone.html`` with a per-trial figure (``trials.png``) of the RMSE they are scored on,
``run.json`` (the seed and the trials) and ``references.npz``.

Where it is (each part imports only from those listed above it; this package's names are theirs):

* ``trials.py``: the hidden trials (:func:`hidden_trials`, :func:`fetch`), the stand-in (:func:`stand_in`) and the
  disguise (:func:`disguise`).
* ``scoring.py``: a trial's metrics (:func:`score_trial`), the reference rows (:func:`references`) and their cache in
  the output folder (:func:`cached_references`), the means and the rubric's points (:func:`rubric_points`).
* ``program.py``: the student's program (:func:`program_of`, :func:`declared_sensors`) and what it may not do
  (:data:`CHEATS`, :func:`scan`, :func:`library_copies`), and the box's library (:func:`placeholder_module`,
  :func:`box_library`).
* ``runner.py``: the box (:func:`box_limits`, :class:`Runner`) and one submission (:func:`grade_submission`,
  :func:`implausibly_close`); ``causality.py``: the causality check it runs (:func:`probe`, :func:`verdict`).
* ``report.py``: the class (:func:`grade_class`), its leaderboard and each student's feedback
  (:func:`write_leaderboard`, :func:`feedback`).
* ``command.py``: the command (:func:`main`), which ``__main__.py`` runs.
"""

from __future__ import annotations

from fusionlab.capstone import (
    CAUSAL_TOL,
    FULL_MARKS,
    GATES,
    MAX_POINTS,
    MIN_SECONDS,
    RUBRIC,
    SECONDS_PER_SAMPLE,
    SENSORS,
    SHIPPED,
    accuracy_points,
    as_quaternions,
    budget_seconds,
    causal_ks,
    first_change,
    prefix_change,
)  # the rules, as the lab states them to the students

from .command import main, read_submissions, saved_seed
from .program import (
    BLOCK_MESSAGE,
    CHEATS,
    COPY_MIN_CHARS,
    DECLARATION,
    EMBED_CHARS,
    FILE_CALLS,
    FILE_IMPORT_OWNERS,
    FILE_MODULE_CALLS,
    FILE_MODULES,
    FILE_OWNERS,
    FILTER_MODULES,
    FUNCTION,
    HIDDEN_PACKAGES,
    IMPLAUSIBLE,
    IMPLAUSIBLE_TRIALS,
    IMPLAUSIBLY_CLOSE,
    KEEP,
    LAB,
    QUIET_MAGICS,
    STUB_MESSAGE,
    WHY_HIDDEN,
    absent_modules,
    as_run,
    box_library,
    declared_sensors,
    library_copies,
    loaders,
    model_program,
    placeholder_module,
    program_of,
    scan,
)
from .report import (
    COLUMNS,
    SETS,
    STYLE,
    TRIAL_COLUMNS,
    feedback,
    grade_class,
    leaderboard_rows,
    trial_rows,
    write_csv,
    write_leaderboard,
)
from .runner import (
    CPU_PER_BUDGET,
    CPU_SLACK_S,
    MAX_RESTARTS,
    NOT_SHOWN,
    SETUP_SECONDS,
    Runner,
    StudentResult,
    _declared_outside,
    _look_for_cheats,
    box_limits,
    error_message,
    gates_failed,
    grade_submission,
    implausibly_close,
    invalid_message,
)
from .causality import Probe, causality_trial, final_cut, plan, prefix_cuts, probe, verdict
from .scoring import (
    CACHE_FORMAT,
    MATCH_RAD,
    MATCH_STRIDE,
    PUBLISHED,
    REFERENCE_CACHE,
    Reference,
    TrialResult,
    cached_references,
    load_references,
    mean_scored,
    mean_total,
    never_moves,
    published_means,
    references,
    references_key,
    references_of,
    rubric_points,
    save_references,
    score_trial,
)
from .trials import (
    DISGUISE_NOISE,
    MAX_CROP_SECONDS,
    MAX_END_CROP_SECONDS,
    CapstoneDataMissing,
    Scored,
    disguise,
    fetch,
    hidden_names,
    hidden_trials,
    stand_in,
)
