#!/usr/bin/env bash
# Builds drape and runs every test: the Release build (ctest), a one-minute fuzz run of the scene loader (libFuzzer
# under ASan + UBSan with its seed corpus, scripts/fuzz.sh), then the whole suite again under AddressSanitizer +
# UndefinedBehaviorSanitizer (asan preset). Run scripts/setup.sh first on a fresh machine.
# Usage: scripts/test.sh [--no-fuzz] [--no-asan]      (DRAPE_FUZZ_SECONDS: length of the fuzz run, default 60)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DRAPE_JOBS:-$(nproc)}
fuzz=1
asan=1
for arg in "$@"; do
    case "$arg" in
    --no-fuzz) fuzz=0 ;;
    --no-asan) asan=0 ;;
    *) echo "test.sh: unknown option '$arg' (options: --no-fuzz, --no-asan)" >&2; exit 2 ;;
    esac
done

# Runs a ctest command; if tests fail, runs only those once more with their output. A test that passes the second time
# is still named (FLAKY, with its first output in the log above) but does not fail the run; one that fails twice does.
ctest_once_more() {
    if "$@"; then return 0; fi
    echo "== some tests failed; running them once more (a second failure is final)"
    if "$@" --rerun-failed --output-on-failure; then
        echo "FLAKY: the tests above failed once and passed when run again: see their first output above"
        return 0
    fi
    return 1
}

echo "== release: configure, build, test"
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
ctest_once_more ctest --preset release -j "$jobs"

if [ "$fuzz" = 1 ]; then
    echo "== fuzz: the scene loader for ${DRAPE_FUZZ_SECONDS:-60} s (libFuzzer, ASan + UBSan)"
    DRAPE_JOBS=$jobs scripts/fuzz.sh "${DRAPE_FUZZ_SECONDS:-60}"
fi

if [ "$asan" = 1 ]; then
    echo "== asan (ASan + UBSan): configure, build, test"
    cmake --preset asan >/dev/null
    # Only what the ASan tests run (the suite and the drape program): the measurement programs (drape_implicit,
    # drape_textile) are built by the Release pass above.
    cmake --build --preset asan -j "$jobs" --target drape drape_tests
    # tests/lsan.supp: allocations made inside the UBSan runtime itself (per-thread data of threads alive at exit).
    # Long physics runs are left to the Release pass above: each repeats, for thousands of steps (or hundreds of
    # frame-long implicit steps), code paths that shorter tests run under the sanitizers too (the grid fabric, the disc
    # and sphere drops, Verlet at rest, the N = 100 strain limit, the 64 x 64 implicit drop; self-collision's folded
    # pile for the crumpled pile, the pushed shirt and the implicit folded cloth; the T-shirt's seam tests for its hem
    # drag; Implicit.SameBitsSeriallyAndAtEveryWorkerCount for the full approximation scheme, the outline cloth's
    # coarse levels and the implicit strain limit, whose come-to-rest and frame-long-step runs are left out; the other
    # built-in scenes' five-second health runs for the drape scene's). Under ASan the first ten took ~800 s of CPU, the
    # last five ~860 s (2026-11-27: the implicit ones 283, 196, 140 and 119 s, the drape scene's 118 s, of 2,586 s for
    # the rest). 2026-11-29 three more (55, 43 and 32 s under ASan): the sewn shirt's 2.5 s settle (the shirt's other
    # sewing tests run under ASan), the N = 100 compression bound and the static-equilibrium settle (the implicit
    # strain limit and the sweeps run in Implicit.SameBitsSeriallyAndAtEveryWorkerCount). 2026-11-29, fourth session:
    # FAS at rest under light drag (461 s under ASan, 6.5 s in Release: 20 s of the N = 100 hang; FAS at rest's rule
    # runs under ASan in Implicit.FasAtRestSameBitsSeriallyAndAtEveryWorkerCount). Others run shorter under
    # ASan (tests/test_helpers.hpp: drape::testing::sanitized). DRAPE_ASAN_ALL=1 runs them as well.
    release_only='^(FabricGrid\.HangsOneSecondHealthyAtN64|MeshCloth\.DiscDropsOntoTheSphereAndStaysHealthy'
    release_only+='|Physics\.VerletSettlesLikeEulerAtRest|StrainLimit\.KeepsMaxStrainWithinTheLimitAtN100'
    release_only+='|Sizes/TriangleContactDrop\.NoTriangleEndsInsideAnyColliderKind/n64_implicit'
    release_only+='|SelfCollision\.CrumpledPileNeverIntersectsItself|SelfCollision\.ShirtFrontPushedIntoTheBackStaysInFront'
    release_only+='|SelfCollision\.ImplicitCrumpledPileInContactSubStepsNeverIntersectsItself|SelfCollision\.ImplicitShirtFrontPushedIntoTheBackStaysInFront'
    release_only+='|SelfCollision\.ImplicitFoldedClothNeverIntersectsItself'
    release_only+='|Implicit\.FasComesToRestOnTheExplicitEquilibrium|Implicit\.StrainLimitHoldsOnFrameLongSteps'
    release_only+='|Implicit\.OutlineClothComesToRestOnItsCoarseLevels|Scenes/BuiltInScene\.StaysHealthyForFiveSeconds/drape'
    release_only+='|TShirtSewn\.HemDraggedThirtyCentimetresAndReleasedStaysOn|TShirtSewn\.ClosesEverySeamSymmetricallyOutsideTheBody'
    release_only+='|TShirtSewn/HemPushed\.IntoTheBodyStopsAtItsSurface/(explicit|implicit)' # 3-10 s in Release; the grab's walk runs under ASan in Physics.GrabbedParticleStaysOutOfColliders
    release_only+='|Implicit\.StrainLimitBoundsCompressionNextToTheClips|Implicit\.SettlesOnTheExplicitStaticEquilibrium'
    release_only+='|Implicit\.AStrainLimitThatCannotHoldAddsNoEnergy' # 14 s in Release
    release_only+='|Implicit\.FasAtRestUnderLightAirDragReachesTheSameRest)( .*)?$'
    exclude=()
    if [ "${DRAPE_ASAN_ALL:-0}" != 1 ]; then exclude=(-E "$release_only"); fi
    ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1} \
    LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp:print_suppressions=0} \
    UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
        ctest_once_more ctest --preset asan -j "$jobs" "${exclude[@]}"
fi
echo "== all tests passed"
