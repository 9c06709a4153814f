"""The equivalent mutants of the modules benchmarks/mutation.py runs on: mutant name ->
(text of the line the mutant makes, why it behaves as the original for every input the
module can get); checked again at every report (docs/mutation.md)."""
from __future__ import annotations

# mutant name -> (text of the line the mutant makes, why it behaves as the original)
_NUMBERS_ARRAY = ("per-run values are numbers (None already replaced or removed): an integer "
                  "array gives the same finite values, means and deviations in float64")
_TAGGED = ("_encode_node has already written every non-finite float as a tagged node, so "
           "json.dumps never meets one whatever its allow_nan")
_CODEC = "codec names are case-insensitive"
_CLEAN = ("scipy's dpotrf zeroes the other triangle by default (clean=1): the factor is the "
          "same (tests/test_innovation_checks.py checks its zeros)")
_FLOATS_LIST = "the list holds Python floats: numpy makes a float64 array of it anyway"
_SQUARE = "the matrix was checked square just before: both sizes are the same"
_CHECKED_NEXT = ("the function called next checks the same matrix against the size and refuses "
                 "it with an error that starts with the same name")
_SAME_LAPACK = ("numpy's cholesky and scipy's dpotrf are the same LAPACK routine in this build "
                "(bit-identical factors in 300 random cases); only a build linking two "
                "different LAPACKs could tell them apart")
_RESTARTED = "__init__ calls restart, which sets both lists before anything reads them"
_FIRST_INCREMENT = ("when checkpoints are dropped the new oldest one is at an IMU epoch after "
                    "the old oldest, so the first stored increment is always at or before it "
                    "and the scan may start at the second")
_NO_INVALID = ("no operation of the middle branch can be invalid: k0/u is inf only at u = 0, "
               "where k1 - u = k1 > 0 (inf, not nan); only the division needs silencing")
_FIND_FROM_MAGIC = ("the search starts after the magic bytes, so find returns -1 or at least "
                    "len(MAGIC): end < 0, end <= 0 and end < 1 agree")
# navcore filters, state and sensor log
_AT_A_FOOT = ("at a foot that is not the vertex the linear edge is 0.0 exactly, the value of the "
              "branch it replaces (a foot at the vertex has returned 1 before)")
_VERTEX_FIRST = "x == vertex has returned 1.0 before: the branch never meets it"
_Z_AT_ZERO = "the Z sets, the only triangles, have their vertex at 0: right + 0 is right - 0"
_LD_NO_RISE = "for LD (j = 0) the rising edge would run from v[-1] = v[4] down to v[0]: no point"
_EDGE_AT_ZERO = ("at the foot of an output set's edge the edge is 0.0, the value the set's zeros "
                 "have there anyway")
_MADE_FLOAT = "_check_probabilities makes the array float64 at once (np.asarray(mu, dtype=float))"
_DISCARDED_DIVISION = ("the divisor stands in for c_bar = 0 only, where the column of joint is "
                       "0 and np.where takes mu instead of the quotient")
_RENORMALIZED = ("with floor 0, np.maximum(mu, 0) is mu, and dividing mu, which sums to 1 "
                 "already, by its sum changes at most its last bit")
_FALSY = "needs_mixing is only read by `if`: None is false as False is"
_AT_T2 = "at stat = T2 the linear branch gives (T2 - T1) / (T2 - T1) = 1.0 exactly"
_FAST_PATHS = ("the first branches are shortcuts: the general branches after them return the "
               "same values (a plain value, a tuple of floats, a copy of a native array)")
_SUBCLASS_ONLY = ("exact ints and floats have returned at the shortcut: here the type is a "
                  "subclass, never int or float itself")
_COPY_DEFAULT = "np.array copies by default (copy=True)"
_CONVERTED_COPY = ("an array reaching this branch is converted from big-endian (a copy anyway) "
                   "or refused just after")
_LITTLE_ENDIAN = ("on a little-endian machine newbyteorder('<') of an array reaching this branch "
                  "is the dtype the condition would pick")
_BIT_GENERATOR = ("a bit generator's state is a dict of str keys, str, ints and int arrays: it is "
                  "never refused, so its path is never printed")
EQUIVALENT: dict[str, tuple[str, str]] = {
    "orchestrator.campaigns.statistics.x_t_interval__mutmut_3": (
        "x = np.array([math.nan if v is None else v for v in values], dtype=None)",
        _NUMBERS_ARRAY),
    "orchestrator.campaigns.statistics.x_t_interval__mutmut_5": (
        "x = np.array([math.nan if v is None else v for v in values], )", _NUMBERS_ARRAY),
    "orchestrator.campaigns.statistics.x_t_interval__mutmut_6": (
        "x = np.array([math.nan if (v is None) and False else v for v in values], dtype=float)",
        "numpy turns None into nan in a float array, as the replaced expression does"),
    "orchestrator.campaigns.statistics.x_positive_interval__mutmut_12": (
        "x = np.array([v for v in values if v is not None], dtype=None)", _NUMBERS_ARRAY),
    "orchestrator.campaigns.statistics.x_positive_interval__mutmut_14": (
        "x = np.array([v for v in values if v is not None], )", _NUMBERS_ARRAY),
    "navcore.core.state_format.x_encode__mutmut_5": ("allow_nan=None).encode(\"utf-8\")", _TAGGED),
    "navcore.core.state_format.x_encode__mutmut_8": (").encode(\"utf-8\")", _TAGGED),
    "navcore.core.state_format.x_encode__mutmut_12": ("allow_nan=True).encode(\"utf-8\")", _TAGGED),
    "navcore.core.state_format.x_encode__mutmut_14": (
        "allow_nan=False).encode(\"UTF-8\")", _CODEC),
    "navcore.core.state_format.x__canonical__mutmut_12": (
        'return json.dumps(header, sort_keys=True, separators=(",", ":")).encode("ASCII")',
        _CODEC),
    "navcore.core.state_format.x__split__mutmut_23": (
        'header = json.loads(raw.decode("ASCII"), parse_constant=_no_constant)', _CODEC),
    "navcore.filters.robust_laws.x_newton_forward_extrapolate__mutmut_9": (
        "a = np.asarray(samples, dtype=None)", _NUMBERS_ARRAY),
    "navcore.filters.robust_laws.x_newton_forward_extrapolate__mutmut_11": (
        "a = np.asarray(samples, )", _NUMBERS_ARRAY),
    "navcore.filters.robust_laws.x_newton_forward_extrapolate__mutmut_49": (
        "return float(result) if (a.ndim == 1) and False else result",
        "for 1-D samples the result is a numpy float64, a subclass of float of the same value"),
    "navcore.filters.robust_laws.x_igg3_weight__mutmut_13": (
        "u = np.abs(np.asarray(standardized_residual, dtype=None))", _NUMBERS_ARRAY),
    "navcore.filters.robust_laws.x_igg3_weight__mutmut_15": (
        "u = np.abs(np.asarray(standardized_residual, ))", _NUMBERS_ARRAY),
    "navcore.filters.robust_laws.x_igg3_weight__mutmut_20": (
        'with np.errstate(divide="ignore", invalid=None):', _NO_INVALID),
    "navcore.filters.robust_laws.x_igg3_weight__mutmut_22": (
        'with np.errstate(divide="ignore", ):', _NO_INVALID),
    "navcore.filters.robust_laws.x_igg3_weight__mutmut_42": (
        "w = np.where(u < k0, 1.0, np.where(u <= k1, middle, 0.0))",
        "at u = k0 the middle branch is (k0/k0) ((k1-k0)/(k1-k0))^2 = 1.0 exactly (continuity)"),
    "navcore.filters.robust_laws.x_igg3_weight__mutmut_50": (
        "w = np.where(u <= k0, 1.0, np.where(u < k1, middle, 0.0))",
        "at u = k1 the middle branch is (k0/k1) 0^2 = 0.0 exactly (continuity)"),
    "navcore.filters.latency.xǁSolutionHistoryǁ__init____mutmut_1": (
        "self.checkpoints: List[Tuple[float, object]] = None", _RESTARTED),
    "navcore.filters.latency.xǁSolutionHistoryǁ__init____mutmut_2": (
        "self.increments: List[Increment] = None", _RESTARTED),
    "navcore.filters.latency.xǁSolutionHistoryǁrecord__mutmut_47": ("n = 1", _FIRST_INCREMENT),
    "navcore.filters.latency.xǁSolutionHistoryǁrecord__mutmut_49": (
        "while n < len(incs) and incs[n][0] <= oldest:".replace("<", "<=", 1),
        "the increment just recorded is after the oldest checkpoint kept (which is at or "
        "before time - keep), so the scan stops before the end of the list"),
    "navcore.filters.adaptive_laws.x_r_floor_from_initial__mutmut_9": (
        "a = np.asarray(R0, dtype=None)", _NUMBERS_ARRAY),
    "navcore.filters.adaptive_laws.x_r_floor_from_initial__mutmut_11": (
        "a = np.asarray(R0, )", _NUMBERS_ARRAY),
    "navcore.filters.adaptive_laws.x_r_floor_from_initial__mutmut_20": (
        "diag = np.diag(a) if a.ndim == 2 else a.reshape(-2)",
        "numpy reads a negative size, -2 as -1, as all the elements"),
    "navcore.filters.adaptive_laws.x_guard_positive_definite__mutmut_9": (
        "m = R.shape[1]", _SQUARE),
    "navcore.filters.adaptive_laws.x_guard_positive_definite__mutmut_12": (
        "floor = np.asarray(R_min, dtype=None)", _NUMBERS_ARRAY),
    "navcore.filters.adaptive_laws.x_guard_positive_definite__mutmut_14": (
        "floor = np.asarray(R_min, )", _NUMBERS_ARRAY),
    "navcore.filters.adaptive_laws.x_fading_predict__mutmut_24": (
        'GQG = square("GQG", GQG, P_propagated.shape[1])', _SQUARE),
    "navcore.filters.adaptive_laws.x_fading_factor__mutmut_31": (
        'R = square("R", R, None)', _CHECKED_NEXT),
    "navcore.filters.adaptive_laws.x_fading_factor__mutmut_34": (
        'R = square("R", R, )', _CHECKED_NEXT),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_14": (
        'G = square("G", G, None)', _CHECKED_NEXT),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_17": (
        'G = square("G", G, )', _CHECKED_NEXT),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_33": (
        'v, L = checked_cholesky(v, G, "G", numpy_factor=None)  # G = L L\', tau = |L^-1 v|^2',
        _SAME_LAPACK),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_37": (
        'v, L = checked_cholesky(v, G, "G", )  # G = L L\', tau = |L^-1 v|^2', _SAME_LAPACK),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_40": (
        'v, L = checked_cholesky(v, G, "G", numpy_factor=False)  # G = L L\', tau = |L^-1 v|^2',
        _SAME_LAPACK),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_59": (
        "Y = 1.0 if tau < gate else math.sqrt(gate / tau)",
        "at tau = gate, sqrt(gate / tau) = sqrt(1.0) = 1.0 exactly"),
    "navcore.filters.adaptive_laws.x_compression_factor__mutmut_84": (
        "Y = 1.0 if tau < gate else D / math.sqrt(tau * lam)",
        "at tau = gate = D^2 / lam, D / sqrt(tau lam) = 1 (Y is continuous at the gate; no "
        "case where tau lands on the gate and round-off moves Y was found)"),
    "navcore.filters.innovation_stats.x_log_det_from_cholesky__mutmut_6": (
        "return 2.0 * sum(math.log(L[i, i]) for i in range(L.shape[1]))", _SQUARE),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_1": (
        "numpy_factor: bool = True) -> Tuple[np.ndarray, np.ndarray]:", _SAME_LAPACK),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_5": (
        "v = np.atleast_1d(np.asarray(innovation, dtype=None))", _NUMBERS_ARRAY),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_7": (
        "v = np.atleast_1d(np.asarray(innovation, ))", _NUMBERS_ARRAY),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_11": (
        "S = np.atleast_2d(np.asarray(S, dtype=None))", _NUMBERS_ARRAY),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_13": (
        "S = np.atleast_2d(np.asarray(S, ))", _NUMBERS_ARRAY),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_28": (
        "L, info = lapack.dpotrf(0.5 * (S + S.T), lower=1, clean=None)", _CLEAN),
    "navcore.filters.innovation_stats.x_checked_cholesky__mutmut_31": (
        "L, info = lapack.dpotrf(0.5 * (S + S.T), lower=1, )", _CLEAN),
    "navcore.filters.innovation_stats.x_chi_square_per_observation__mutmut_3": (
        "v = np.asarray(innovation, dtype=None)", _NUMBERS_ARRAY),
    "navcore.filters.innovation_stats.x_chi_square_per_observation__mutmut_5": (
        "v = np.asarray(innovation, )", _NUMBERS_ARRAY),
    "navcore.sensors.log_time.x_relative_seconds__mutmut_5": ("dtype=None)", _FLOATS_LIST),
    "navcore.sensors.log_time.x_relative_seconds__mutmut_7": (")", _FLOATS_LIST),
    "navcore.sensors.log_time.x_check_intervals__mutmut_19": (
        'kind = ("a gap (a lost sample?)" if deviation[k] >= 0 else',
        "a refused interval deviates by more than max_dt_jitter >= 0, so never by exactly 0"),
    "navcore.sensors.log_time.x__reaching_step__mutmut_9": (
        "tol = max(time_tolerance(step, ), time_tolerance(step, float(ends[-1])))",
        "the ends increase, so the tolerance at the last end is at least that at t = 0: the "
        "max is the second term either way"),
    "navcore.core.state_format.x_decode__mutmut_32": (
        'node = json.loads(payload.decode("UTF-8"), parse_constant=_no_constant)', _CODEC),
    "navcore.core.state_format.x__split__mutmut_13": ("if end <= 0:", _FIND_FROM_MAGIC),
    "navcore.core.state_format.x__split__mutmut_14": ("if end < 1:", _FIND_FROM_MAGIC),
    # navcore filters, state and sensor log
    "navcore.filters.fuzzy.x__shoulder_left__mutmut_3": (
        'if x > right:', _AT_A_FOOT),
    "navcore.filters.fuzzy.x__shoulder_right__mutmut_3": (
        'if x < left:', _AT_A_FOOT),
    "navcore.filters.fuzzy.x__triangle__mutmut_4": (
        'if x < left or x >= right:', _AT_A_FOOT),
    "navcore.filters.fuzzy.x__triangle__mutmut_5": (
        'if x <= left or x > right:', _AT_A_FOOT),
    "navcore.filters.fuzzy.x__triangle__mutmut_7": (
        'if x < vertex:', _VERTEX_FIRST),
    "navcore.filters.fuzzy.x__triangle__mutmut_13": (
        'return (right - x) / (right + vertex)', _Z_AT_ZERO),
    "navcore.filters.fuzzy.xǁFuzzyRScaleǁ__init____mutmut_61": (
        'if j >= 0:', _LD_NO_RISE),
    "navcore.filters.fuzzy.xǁFuzzyRScaleǁ__init____mutmut_65": (
        'rise = (grid > v[j - 1]) & (grid <= v[j])', _EDGE_AT_ZERO),
    "navcore.filters.fuzzy.xǁFuzzyRScaleǁ__init____mutmut_82": (
        'fall = (grid >= v[j]) & (grid < v[j + 1])', _EDGE_AT_ZERO),
    "navcore.filters.imm.x_check_transition_matrix__mutmut_3": (
        'Pi = np.array(Pi, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_check_transition_matrix__mutmut_5": (
        'Pi = np.array(Pi, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x__check_probabilities__mutmut_3": (
        'mu = np.asarray(mu, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x__check_probabilities__mutmut_5": (
        'mu = np.asarray(mu, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_mix__mutmut_15": (
        'X = np.asarray(xs, dtype=None)                  # (r, n)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_mix__mutmut_17": (
        'X = np.asarray(xs, )                  # (r, n)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_mix__mutmut_20": (
        'Parr = np.asarray(Ps, dtype=None)               # (r, n, n)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_mix__mutmut_22": (
        'Parr = np.asarray(Ps, )               # (r, n, n)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_update_probabilities__mutmut_4": (
        'c_bar = np.asarray(c_bar, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_update_probabilities__mutmut_6": (
        'c_bar = np.asarray(c_bar, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_update_probabilities__mutmut_9": (
        'lik = np.asarray(likelihoods, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_update_probabilities__mutmut_11": (
        'lik = np.asarray(likelihoods, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_combine__mutmut_3": (
        'mu = np.asarray(mu, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_combine__mutmut_5": (
        'mu = np.asarray(mu, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_combine__mutmut_8": (
        'X = np.asarray(xs, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_combine__mutmut_10": (
        'X = np.asarray(xs, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_combine__mutmut_13": (
        'Parr = np.asarray(Ps, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_imm_combine__mutmut_15": (
        'Parr = np.asarray(Ps, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.xǁImmBankǁsubtract_from_states__mutmut_3": (
        'delta = np.asarray(delta, dtype=None)', _NUMBERS_ARRAY),
    "navcore.filters.imm.xǁImmBankǁsubtract_from_states__mutmut_5": (
        'delta = np.asarray(delta, )', _NUMBERS_ARRAY),
    "navcore.filters.imm.x_check_transition_matrix__mutmut_15": (
        'if Pi.ndim != 2 or Pi.shape[0] != Pi.shape[1] or (r is not None and Pi.shape[1] != r):',
        _SQUARE),
    "navcore.filters.imm.xǁImmBankǁ__init____mutmut_25": (
        'self.mu = _check_probabilities(np.array(mu0, dtype=None), "mu0").copy()', _MADE_FLOAT),
    "navcore.filters.imm.xǁImmBankǁ__init____mutmut_27": (
        'self.mu = _check_probabilities(np.array(mu0, ), "mu0").copy()', _MADE_FLOAT),
    "navcore.filters.imm.x_imm_mix__mutmut_45": (
        'reachable, joint / np.where(reachable, c_bar, 2.0), mu[:, None]', _DISCARDED_DIVISION),
    "navcore.filters.imm.x_imm_update_probabilities__mutmut_70": (
        'if floor >= 0.0:', _RENORMALIZED),
    "navcore.filters.imm.xǁImmBankǁmix__mutmut_19": (
        'self.needs_mixing = None', _FALSY),
    "navcore.filters.ctfa.x_ctfa_q_scale__mutmut_23": (
        'if stat >= T2:', _AT_T2),
    "navcore.core.state.x_capture_value__mutmut_1": (
        'kind = None', _FAST_PATHS),
    "navcore.core.state.x_capture_value__mutmut_15": (
        'if kind is tuple and all(type(None) is float for v in value):   #'
        ' e.g. a 3-vector of floats',
        _FAST_PATHS),
    "navcore.core.state.x_capture_value__mutmut_19": (
        'return value if (type(value) in (int, float)) and False else _python_scalar(value)',
        _SUBCLASS_ONLY),
    "navcore.core.state.x_capture_value__mutmut_21": (
        'return value if type(None) in (int, float) else _python_scalar(value)', _SUBCLASS_ONLY),
    "navcore.core.state.x_capture_value__mutmut_10": (
        'return np.array(value, )', _COPY_DEFAULT),
    "navcore.core.state.x_capture_value__mutmut_38": (
        'return np.array(value, dtype=dtype, )', _COPY_DEFAULT),
    "navcore.core.state.x_copy_value__mutmut_4": (
        'return np.array(node, )', _COPY_DEFAULT),
    "navcore.core.state.x_capture_value__mutmut_35": (
        'return np.array(value, dtype=dtype, copy=None)', _CONVERTED_COPY),
    "navcore.core.state.x_capture_value__mutmut_27": (
        'dtype = value.dtype.newbyteorder("<") if (value.dtype.byteorder =='
        ' ">") or True else value.dtype',
        _LITTLE_ENDIAN),
    "navcore.core.state.x_capture_value__mutmut_41": (
        'return capture_value(value.bit_generator.state, None)', _BIT_GENERATOR),
}

# orchestrator campaigns and exchange
_FLOAT_ALREADY = ("the values meet float64 arrays (the range hi - lo, 1 / cost, the float64 "
                  "population row they are assigned into): the result is float64 whatever "
                  "the dtype of the converted array")
_DRAW_EQUALS_P = ("rng.random() < p and <= p differ only for a draw exactly equal to p, "
                  "probability 2**-53 per draw")
_GA = "orchestrator.campaigns.genetic.x"
_TUNE = "orchestrator.campaigns.tune.x"
_UNUSED_BACKEND = "_declared_ranges does not read its backend argument"
_RANGE_DTYPE = ("lo and hi only meet float arithmetic (decode, the current values' genes) "
                "and float() in the summary: an integer array of a range gives the same values")
_JSON_LAYOUT = "only the layout of tune.json's text changes; its readers parse the JSON"
_CAMPAIGN = "orchestrator.campaigns.campaign.x"
_CAMPAIGN_RUNS = "orchestrator.campaigns.campaign_runs.x"
_SEEDS = "orchestrator.campaigns.seeds.x"
_GIT_TIMEOUT = "the timeout only bounds a git that hangs; git answers in milliseconds here"
_STATUS_CHECK = ("git status cannot fail in a folder where git rev-parse HEAD (checked) has "
                 "just succeeded")
_STATUS_BYTES = "the status output is only tested for being blank: bytes or text alike"
_PATHSPEC = ("'--' only separates the paths from options: as a pathspec it matches no file, "
             "and no path given starts with '-'")
_FMU_REGISTRY = ("Simulation reads the registry only on the direct backend (the fmu backend "
                 "describes the FMU files)")
_FALSY_SEP = "sep is only tested for truth: None and '' are both false"
# filter helpers and log converters
_INIT = "navcore.filters.initial_state.x"
_FLOAT_PRODUCT = ("the integer array meets a float (a DCM, a float division, a square root of "
                  "a sum with floats) before any result: the same float64 values")
_SCALE_FREE = ("leveling and gyrocompassing are atan2 of ratios of the mean's components: a "
               "positive time (> 0 there) times the sum gives the angles of the sum / time")
_ONLY_WRITTEN = ("the initializer's warned flag is written by the filter shell and saved with "
                 "the state, never read")
_THREE_OR_SIX = ("the fix sigmas are 3 (position) or 6 (with velocity) values: the slice "
                 "3:7 of six values is 3:6, 0:4 of three is 0:3")
_LC = "navcore.sensors.log_converters.x"
_COMMENT_SPLIT = "only the text before the first '#' is kept: [0] of any split at '#' is it"
_PARSED_FLOATS = "parse_numbers returns Python floats: numpy makes a float64 array of them anyway"
_FLOAT_RATES = ("the callers pass float arrays (rates times a float constant, read from text); "
                "0.5 * dt makes the result float, with integers exact below 2**53")
_LOCAL_FRAME_DEFAULT = "an empty first column does not start with gps_x, as 'XXXX' does not"
_BOOL_AS_FLOAT = "astype(None) is astype(float64), numpy's default dtype"
_EXTRA_LINE = ("one line number more than rows: only the rows' entries are read (_line(data, k) "
               "for a row k)")
_DEFAULT_LINE = ("check_log's default line of row k is k + 2, the line numbers given here for "
                 "the fixes (gps_time.csv) and the truth (time.csv)")
_NAMED_SOURCES = ("every file check_log names here is in sources; the where of _check_columns "
                  "is never printed: the converter always gives every column")
_ONE_SAMPLE_SPAN = ("a table has at least one row here (no samples are refused before); for one "
                    "row t[-1] - t[0] = 0 and a span of 1.0 gives the same rate 0")
# the exchange without test_master.py's CSV test
_EXCH = "orchestrator.cosim.exchange.x"
_NO_PATH_THROUGH_ORDERED = ("an ordered component has no active connection from a remaining "
                            "one (that would have kept it blocked), so no path from a "
                            "remaining component runs through an ordered one: the edges "
                            "touching it change no reachability the cycle break reads")
_KEYS_ONLY = "only the keys of delayed are read (id(c) in delayed)"
_IN_RANGE = ("every source index is a position in the signal vector (slots_for builds them "
             "from the outputs' positions): take's mode never acts")
_UNIFORM_SHORTCUT = ("the shared period is a shortcut: the masked copy with every input's "
                     "period, taken without it, copies the same inputs")
_INT64 = "on a 64-bit Linux np.intp and numpy's default integer are int64"
_GS_STEPS = "GaussSeidel keeps n_steps but never reads it (only Jacobi's windows do)"
_ZERO_SPAN = ("with a span of 0 an update leaves the window as soon as it is added (its time "
              "is <= t - 0), so the window never holds MIN_UPDATES: no warning either way")
_CAMPAIGN_JSON_LAYOUT = "only the layout of the JSON text changes; its readers parse it"
_ASCII_JSON = ("json.dumps writes ASCII (ensure_ascii): the file reads the same in UTF-8 and "
               "in the locale's ASCII-compatible encoding")
_RUNS_AT_LEAST_ONE = "runs = max(--runs, default) and --runs >= 1: a default of 0 or 1 agrees"
# Kf engines and recovery
_KF = "navcore.filters.ins_gnss_kf.xǁKfEngineǁ"
_EINSUM_CASE = "einsum subscripts are letters of either case: 'IJ,IJ->I' is the same contraction"
_SLICE_PAST_M = ("z has m = 6 elements here: the slice 3:7 stops at its end, as 3:6 does")
_RECOVERY = "navcore.filters.recovery.x"
_NIS_AT_TARGET = ("with the NIS at lambda = 1 equal to the target every bisection step sets "
                  "hi = mid (the NIS is at most the target for lambda > 1): hi ends at "
                  "log(1e6) / 2^60 = 1.2e-17, whose exp is 1.0, the value returned early")
_SAME_INTERVAL = "a gap equal to the interval sets the interval to the value it has"
_ADAPTIVE = "navcore.filters.adaptive_filters.x"
_ROBUST = "navcore.filters.robust_filters.x"
_LEVEL_CHECK_ONLY = ("the call only checks the level alpha (its quantile is discarded); "
                     "the default dof 1 is as valid as m")
_UNIT_Y = "Y v with Y = 1.0 is v to the last bit"
_NEWEST_SAMPLES = ("newton_forward_extrapolate reads only the newest newton_order + 1 samples "
                   "(table = a[n - p - 1:]), so an older sample kept is never read")
_TRIMMED = ("after every append the loop trims sample_variances to the history's length, at "
            "most newton_order + 1")
_FIRST_EPOCH = ("history_epoch is first read in _next_epoch after last_update_time is set, "
                "and the first call (last_update_time None) sets it to 0 without reading it")
_SMALL_BINOMIALS = ("the binomial weights are integers of at most C(11, 5) = 462 "
                    "(newton_order <= 10, its limits; int64 squares stay exact up to order "
                    "33): exact squares, promoted to the same float64 in the product with "
                    "the variances")
_ALL_VARIANCES = ("sample_variances holds at most newton_order + 1 values, so p + 1 is its "
                  "length and both slices take all of it")
# UKF engines
_UNSCENTED = "navcore.filters.unscented.x"
_UKF = _UNSCENTED + "ǁUnscentedKalmanFilterǁ"
_CLEAN_DEFAULT = ("scipy's dpotrf reads clean=None, as a clean left out, as its default clean=1 "
                  "(the other triangle zeroed): the same factor")
_MODEL_NUMBERS = ("the states, covariances, measurements and model outputs are numbers: an "
                  "integer array meets float weights or float arrays in every use and gives "
                  "the same values")
_UNIT_SCALE = "a scale of 1.0 times the matrix is the matrix exactly: the branch saves a product"
_UKF_FILTERS = "navcore.filters.ukf_filters.x"
_UKF_TIME_UPDATE = "navcore.filters.ukf_time_update.x"
_STAND_IN = ("the stand-in for a small angle only keeps the closed form finite where np.where "
             "takes the series instead")
_ROWS_READ = "only rows 0-2 of it are read (dr[0], dr[2]; phi[_NEXT], phi[_PREV])"
_FIFTEEN = "the state has 15 components: the slice 12:16 is 12:15"
_DEFAULT_ZEROS = "the filter's default initial state is zeros(n), the one passed"
# Campaign summary, sweep and executor
_SUMMARY = "orchestrator.campaigns.campaign_summary.x"
_MISSION_LAST = ("the mission axes, the only ones without a paper key, are the last of AXES: "
                 "stopping at the first of them skips the same axes as skipping each")
_SWEEP = "orchestrator.campaigns.sweep.x"
_DIRECT_ONLY = ("simulate_scenario reads build and log only on the fmu backend (to build the "
                "FMUs first); run_point always runs on the direct backend")
_NAN_SPELLING = "float() reads 'nan' in any case: float('NAN') is the same nan"
_GRID_ON = ("matplotlib turns the grid on when line properties (alpha) are given and the "
            "first argument is None or left out")
EQUIVALENT.update({
    _GA + "_decode__mutmut_4": ("return lo + np.asarray(genes, dtype=None) * (hi - lo)",
                                _FLOAT_ALREADY),
    _GA + "_decode__mutmut_6": ("return lo + np.asarray(genes, ) * (hi - lo)", _FLOAT_ALREADY),
    _GA + "_roulette__mutmut_3": ("fitness = np.asarray(fitness, dtype=None)", _FLOAT_ALREADY),
    _GA + "_roulette__mutmut_5": ("fitness = np.asarray(fitness, )", _FLOAT_ALREADY),
    _GA + "ǁGeneticAlgorithmǁ_offspring__mutmut_3": (
        "fitness = 2.0 / np.asarray(cost)",
        "roulette draws with p = fitness / fitness.sum(): a common factor 2 cancels exactly"),
    _GA + "ǁGeneticAlgorithmǁ_offspring__mutmut_8": (
        "while len(children) <= self.population:",
        "one more pair is bred and dropped by children[:self.population]: other draws of the "
        "seeded stream are used, the operators and their distribution are the same"),
    _GA + "ǁGeneticAlgorithmǁ_offspring__mutmut_18": (
        "if rng.random() <= self.crossover_probability:", _DRAW_EQUALS_P),
    _GA + "ǁGeneticAlgorithmǁ_offspring__mutmut_30": (
        "if rng.random() <= self.mutation_probability:", _DRAW_EQUALS_P),
    _GA + "ǁGeneticAlgorithmǁrun__mutmut_5": (
        'result = GaResult(None, float("inf"))',
        "the first generation's best cost is finite (checked), so < inf: its genes replace "
        "the initial result before anything reads it"),
    _GA + "ǁGeneticAlgorithmǁrun__mutmut_12": (
        'result = GaResult(np.zeros(self.n_genes), float("INF"))',
        "float() reads 'inf' case-insensitively"),
    _GA + "ǁGeneticAlgorithmǁrun__mutmut_25": (
        "pop[i] = np.clip(np.asarray(row, dtype=None), 0.0, 1.0)", _FLOAT_ALREADY),
    _GA + "ǁGeneticAlgorithmǁrun__mutmut_27": (
        "pop[i] = np.clip(np.asarray(row, ), 0.0, 1.0)", _FLOAT_ALREADY),
    _GA + "ǁGeneticAlgorithmǁrun__mutmut_71": (
        "if cost[best] <= result.best_cost:",
        "a tie needs cost[best] == best so far; from generation 2 row 0 is the elite with "
        "that cost and argmin returns the first of equal minima, so the same genes are kept"),
    _TUNE + "_resolve_parameters__mutmut_6": (
        "declared = _declared_ranges(model, component, None)", _UNUSED_BACKEND),
    _TUNE + "__seed_parameters__mutmut_5": (
        "declared = _declared_ranges(model, c.name, None)", _UNUSED_BACKEND),
    _TUNE + "__tuning_spec__mutmut_24": ("None)", _UNUSED_BACKEND),
    _TUNE + "__tuning_spec__mutmut_57": (
        "window, _seed_parameters(model, None) if train_seeds else ())", _UNUSED_BACKEND),
    _TUNE + "_resolve_parameters__mutmut_37": (
        "return np.array(lo, None), np.array(hi, float), tuple(types), np.array(current)",
        _RANGE_DTYPE),
    _TUNE + "_resolve_parameters__mutmut_39": (
        "return np.array(lo, ), np.array(hi, float), tuple(types), np.array(current)",
        _RANGE_DTYPE),
    _TUNE + "_resolve_parameters__mutmut_41": (
        "return np.array(lo, float), np.array(hi, None), tuple(types), np.array(current)",
        _RANGE_DTYPE),
    _TUNE + "_resolve_parameters__mutmut_43": (
        "return np.array(lo, float), np.array(hi, ), tuple(types), np.array(current)",
        _RANGE_DTYPE),
    _TUNE + "_evaluate__mutmut_17": (
        'registry=registry() if (spec.backend == "direct") or True else None,',
        "Simulation reads the registry only on the direct backend (the fmu backend "
        "describes the FMU files)"),
    _TUNE + "_write_tune_outputs__mutmut_46": (
        "lambda f: f.write(json.dumps(summary, indent=None))),", _JSON_LAYOUT),
    _TUNE + "_write_tune_outputs__mutmut_48": (
        "lambda f: f.write(json.dumps(summary, ))),", _JSON_LAYOUT),
    _TUNE + "_write_tune_outputs__mutmut_49": (
        "lambda f: f.write(json.dumps(summary, indent=3))),", _JSON_LAYOUT),
    _CAMPAIGN + "_code_commit__mutmut_7": (
        "capture_output=True, text=True, timeout=None).stdout.strip()", _GIT_TIMEOUT),
    _CAMPAIGN + "_code_commit__mutmut_12": (
        "capture_output=True, text=True, ).stdout.strip()", _GIT_TIMEOUT),
    _CAMPAIGN + "_code_commit__mutmut_25": (
        "capture_output=True, text=True, timeout=31).stdout.strip()", _GIT_TIMEOUT),
    _CAMPAIGN + "_code_commit__mutmut_31": (
        "check=True, capture_output=True, text=True, timeout=None).stdout", _GIT_TIMEOUT),
    _CAMPAIGN + "_code_commit__mutmut_36": (
        "check=True, capture_output=True, text=True, ).stdout", _GIT_TIMEOUT),
    _CAMPAIGN + "_code_commit__mutmut_58": (
        "check=True, capture_output=True, text=True, timeout=31).stdout", _GIT_TIMEOUT),
    _CAMPAIGN + "_code_commit__mutmut_28": (
        "check=None, capture_output=True, text=True, timeout=30).stdout", _STATUS_CHECK),
    _CAMPAIGN + "_code_commit__mutmut_33": (
        "capture_output=True, text=True, timeout=30).stdout", _STATUS_CHECK),
    _CAMPAIGN + "_code_commit__mutmut_55": (
        "check=False, capture_output=True, text=True, timeout=30).stdout", _STATUS_CHECK),
    _CAMPAIGN + "_code_commit__mutmut_30": (
        "check=True, capture_output=True, text=None, timeout=30).stdout", _STATUS_BYTES),
    _CAMPAIGN + "_code_commit__mutmut_35": (
        "check=True, capture_output=True, timeout=30).stdout", _STATUS_BYTES),
    _CAMPAIGN + "_code_commit__mutmut_57": (
        "check=True, capture_output=True, text=False, timeout=30).stdout", _STATUS_BYTES),
    _CAMPAIGN + "_code_commit__mutmut_48": (
        "\"--untracked-files=no\", \"XX--XX\", \"fmus\", \"orchestrator\", \"models\"],",
        _PATHSPEC),
    _SEEDS + "_random_components__mutmut_11": (
        "sim = Simulation(model, backend=backend, registry=registry() if (backend == "
        "\"direct\") or True else None,", _FMU_REGISTRY),
    _CAMPAIGN_RUNS + "_run_one__mutmut_36": (
        "registry=registry() if (job[\"backend\"] == \"direct\") or True else None,",
        _FMU_REGISTRY),
    _SEEDS + "_parse_seed_offsets__mutmut_8": (
        "sep = None", _FALSY_SEP),
    _CAMPAIGN_RUNS + "_write_run__mutmut_25": (
        "return atomic_write(path, lambda f: f.write(json.dumps(jsonable(record), ind"
        "ent=None)))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN_RUNS + "_write_run__mutmut_27": (
        "return atomic_write(path, lambda f: f.write(json.dumps(jsonable(record), )))",
        _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN_RUNS + "_write_run__mutmut_29": (
        "return atomic_write(path, lambda f: f.write(json.dumps(jsonable(record), ind"
        "ent=2)))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN + "_run_campaign__mutmut_48": (
        "lambda f: f.write(json.dumps(jsonable(summary), indent=None)))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN + "_run_campaign__mutmut_50": (
        "lambda f: f.write(json.dumps(jsonable(summary), )))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN + "_run_campaign__mutmut_52": (
        "lambda f: f.write(json.dumps(jsonable(summary), indent=2)))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN + "ǁCampaignǁwrite_manifest__mutmut_15": (
        "indent=None)))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN + "ǁCampaignǁwrite_manifest__mutmut_17": (
        ")))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN + "ǁCampaignǁwrite_manifest__mutmut_25": (
        "indent=3)))", _CAMPAIGN_JSON_LAYOUT),
    _CAMPAIGN_RUNS + "_read_run__mutmut_10": (
        "record = json.loads(path.read_text(encoding=None))", _ASCII_JSON),
    _CAMPAIGN_RUNS + "_read_run__mutmut_12": (
        "record = json.loads(path.read_text(encoding=\"UTF-8\"))", _ASCII_JSON),
    _CAMPAIGN + "ǁCampaignǁ_check_manifest__mutmut_8": (
        "old = json.loads(path.read_text(encoding=None))", _ASCII_JSON),
    _CAMPAIGN + "ǁCampaignǁ_check_manifest__mutmut_10": (
        "old = json.loads(path.read_text(encoding=\"UTF-8\"))", _ASCII_JSON),
    _CAMPAIGN + "ǁCampaignǁ_check_manifest__mutmut_52": (
        "runs = max(runs, int(old.get(\"runs\", 1)))", _RUNS_AT_LEAST_ONE),
    "orchestrator.cosim.exchange.xǁJacobiǁ__init____mutmut_8": (
        "self._pending_ns = [1] * len(self.slots)",
        "never read before written: a window read at the end of step k (n | k + 1) started "
        "at k + 1 - n, which is due and ends by the stop, so it set its entry"),
    # Kf engines and recovery
    _KF + "covariance_diagonal__mutmut_10": (
        'return np.einsum("IJ,IJ->I", a @ self.P, a) + np.diagonal(self.q_acc)', _EINSUM_CASE),
    _KF + "measurement__mutmut_36": ("z[3:7] = v - fix_v_ned", _SLICE_PAST_M),
    _KF + "measurement__mutmut_52": (
        "z[3:7] += antenna_velocity_offset(nav.C_bn, lever, self.rate_ib, nav.lat)",
        _SLICE_PAST_M),
    _RECOVERY + "_inflation_factor__mutmut_36": ("if nis_at(1.0) < target:", _NIS_AT_TARGET),
    _RECOVERY + "ǁRecoveryGuardǁopen_epoch__mutmut_10": (
        "if gap > 0.0 and (self.interval == 0.0 or gap <= self.interval):", _SAME_INTERVAL),
    _ADAPTIVE + "ǁIakfEngineǁ__init____mutmut_9": (
        "chi2_gate(outlier_alpha, )   # checks the level (compression_factor gates)",
        _LEVEL_CHECK_ONLY),
    _ADAPTIVE + "ǁIakfEngineǁupdate__mutmut_39": (
        "v_used = v if (Y == 1.0) and False else Y * v                        # paper 001 eq. 13",
        _UNIT_Y),
    _ADAPTIVE + "ǁIakfEngineǁupdate__mutmut_42": (
        "v_used = v if Y == 2.0 else Y * v                        # paper 001 eq. 13", _UNIT_Y),
    _ROBUST + "ǁNewtonRobustKfEngineǁ__init____mutmut_17": (
        "self.history = robust_laws.ObservationHistory(maxlen=self.newton_order + 2)",
        _NEWEST_SAMPLES),
    _ROBUST + "ǁNewtonRobustKfEngineǁ__init____mutmut_19": (
        "self.sample_variances = deque(maxlen=None)", _TRIMMED),
    _ROBUST + "ǁNewtonRobustKfEngineǁ__init____mutmut_21": (
        "self.sample_variances = deque(maxlen=self.newton_order + 2)", _TRIMMED),
    _ROBUST + "ǁNewtonRobustKfEngineǁ__init____mutmut_26": (
        "self.history_epoch = None", _FIRST_EPOCH),
    _ROBUST + "ǁNewtonRobustKfEngineǁ__init____mutmut_27": (
        "self.history_epoch = 1", _FIRST_EPOCH),
    _ROBUST + "ǁNewtonRobustKfEngineǁ_extrapolated_variance__mutmut_12": (
        "weights = np.array([math.comb(p + 1, j + 1) for j in range(p + 1)], dtype=None)",
        _SMALL_BINOMIALS),
    _ROBUST + "ǁNewtonRobustKfEngineǁ_extrapolated_variance__mutmut_14": (
        "weights = np.array([math.comb(p + 1, j + 1) for j in range(p + 1)], )",
        _SMALL_BINOMIALS),
    _ROBUST + "ǁNewtonRobustKfEngineǁ_extrapolated_variance__mutmut_30": (
        "newest_first = variances[::-1][:p + 2]", _ALL_VARIANCES),
    # UKF engines
    _UNSCENTED + "__sqrt_symmetric__mutmut_4": (
        "L, info = lapack.dpotrf(A, lower=1, clean=None)", _CLEAN_DEFAULT),
    _UNSCENTED + "__sqrt_symmetric__mutmut_7": (
        "L, info = lapack.dpotrf(A, lower=1, )", _CLEAN_DEFAULT),
    _UKF + "correct__mutmut_43": ("Ls, info = lapack.dpotrf(S, lower=1, clean=None)",
                                  _CLEAN_DEFAULT),
    _UKF + "correct__mutmut_46": ("Ls, info = lapack.dpotrf(S, lower=1, )", _CLEAN_DEFAULT),
    _UNSCENTED + "_sigma_points__mutmut_3": ("x = np.asarray(x, dtype=None)", _MODEL_NUMBERS),
    _UNSCENTED + "_sigma_points__mutmut_5": ("x = np.asarray(x, )", _MODEL_NUMBERS),
    _UNSCENTED + "_sigma_points__mutmut_8": ("P = np.asarray(P, dtype=None)", _MODEL_NUMBERS),
    _UNSCENTED + "_sigma_points__mutmut_10": ("P = np.asarray(P, )", _MODEL_NUMBERS),
    _UNSCENTED + "_unscented_transform__mutmut_3": (
        "points = np.asarray(points, dtype=None)", _MODEL_NUMBERS),
    _UNSCENTED + "_unscented_transform__mutmut_5": (
        "points = np.asarray(points, )", _MODEL_NUMBERS),
    _UNSCENTED + "__apply_model__mutmut_3": (
        "Y = np.asarray(func(X, *args), dtype=None)", _MODEL_NUMBERS),
    _UNSCENTED + "__apply_model__mutmut_5": ("Y = np.asarray(func(X, *args), )", _MODEL_NUMBERS),
    _UNSCENTED + "__apply_model__mutmut_16": (
        "return np.array([np.atleast_1d(func(xi, *args)) for xi in X], dtype=None)",
        _MODEL_NUMBERS),
    _UNSCENTED + "__apply_model__mutmut_18": (
        "return np.array([np.atleast_1d(func(xi, *args)) for xi in X], )", _MODEL_NUMBERS),
    _UKF + "predict_points__mutmut_4": ("Y = np.asarray(Y, dtype=None)", _MODEL_NUMBERS),
    _UKF + "predict_points__mutmut_6": ("Y = np.asarray(Y, )", _MODEL_NUMBERS),
    _UKF + "predict_points__mutmut_21": (
        "P += Q if (q_scale == 1.0) and False else q_scale * np.asarray(Q)", _UNIT_SCALE),
    _UKF + "correct__mutmut_4": ("z = np.asarray(z, dtype=None)", _MODEL_NUMBERS),
    _UKF + "correct__mutmut_6": ("z = np.asarray(z, )", _MODEL_NUMBERS),
    _UKF + "correct__mutmut_24": (
        "S = Pzz + (R if (r_scale == 1.0) and False else r_scale * np.asarray(R))", _UNIT_SCALE),
    _UKF_TIME_UPDATE + "__rodrigues_coefficients__mutmut_21": (
        "safe = np.where(small, 2.0, theta)", _STAND_IN),
    _UKF_TIME_UPDATE + "__inverse_jacobian_apply__mutmut_12": (
        "theta = np.sqrt(np.where(small, 2.0, theta2))", _STAND_IN),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_6": (
        "dr, dv, phi = Xt[0:4], Xt[3:6], Xt[6:9]", _ROWS_READ),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_10": (
        "dr, dv, phi = Xt[0:3], Xt[3:6], Xt[6:10]", _ROWS_READ),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_65": (
        'theta2 = np.einsum("IJ,IJ->I", phi_rows, phi_rows)',
        "einsum's subscripts are labels: IJ,IJ->I is the same sum as ij,ij->i"),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_72": (
        "V = np.empty((4, 3, X.shape[0]))",
        "a fourth slice of V is rotated along elementwise and never read: RV[0..2] are the same"),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_90": ("V[2] = (X[:, 12:16] @ C_t).T", _FIFTEEN),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_183": (
        "Xdot_t[12:16] = 0.0 if tau_a <= 0 else -Xt[12:15] / tau_a", _FIFTEEN),
    _UKF_TIME_UPDATE + "__error_dynamics__mutmut_192": (
        "Xdot_t[12:15] = 0.0 if tau_a <= 0 else -Xt[12:16] / tau_a", _FIFTEEN),
    _UKF_FILTERS + "ǁUkfEngineǁ_new_ukf__mutmut_5": ("x0=None, P0=self.P.copy())", _DEFAULT_ZEROS),
    _UKF_FILTERS + "ǁUkfEngineǁ_new_ukf__mutmut_11": ("P0=self.P.copy())", _DEFAULT_ZEROS),
    _UKF_FILTERS + "ǁCtfaUkfEngineǁ__init____mutmut_42": (
        "self.schedule = CtfaQSchedule(np.eye(1), self.q_max_scale / np.eye(1), T1, T2,",
        "the 1 x 1 identity: q_max_scale over it is q_max_scale times it, exactly"),
})

# AHRS engines and sensor logs
_SL = "navcore.sensors.sensorlog.x"
_SPLITLINES = ("the lines are split by str.splitlines, which breaks at \\r, \\n and \\r\\n as "
               "universal newlines translate them: the same lines either way")
_ASCII_TEXT = ("the text written is ASCII (titles, %.17g numbers, Decimal times): every locale "
               "encoding Python runs under writes the same bytes")
_LINESEP = ("newline=None writes os.linesep, '\\n' on POSIX; a '\\r\\n' of Windows reads back "
            "the same (str.splitlines)")
_LAST_FILE = ("only the truth table can be None (imu and gnss are read or refused), and it is "
              "the last of the loop: nothing is left to skip")
_PARTLY = ("a group is partly present exactly when it is partly absent: the condition holds "
           "for the present and the absent columns alike, and the message names the first "
           "absent one either way")
_NONZERO_GAP = ("a refused gap has |gap| > IMU_GAP_TOLERANCE dt > 0 (dt > 0 checked above): it "
                "is never 0")
_ORIGIN_PASSED = "write_log, the only caller, always passes the log's origin"
_PARENT_NEVER_EMPTY = ("Path.parent is never the empty path (str gives '.' for a bare name): the "
                       "else branch is never taken")
_UMASK_RESTORED = ("os.umask returns the mask it replaces whatever it sets, and the next call "
                   "restores that mask")
_AHRS = "navcore.filters.ahrs.x"
_FLOAT_INPUTS = ("the AHRS component passes float64 arrays built from its Real inputs: the "
                 "conversion returns them as they are")
_NAN_REFUSED = ("a zero f_b makes down, east and |east| nan, and nan > 0 is false: the second "
                "test refuses it as the first does")
_LAST_AXIS = "the stacked components are 1-D (one value per row): axis 1 is the last axis"
_SERIES_STAND_IN = ("the stand-in divisor of the series branch: np.where takes the series "
                    "there and discards the quotient")
_NEVER_READ = "inclination is never read after __init__ (field_unit holds it), nor saved"
_NIS_SET_FIRST = ("last_nis is read (the component's nis output) only after an update has set "
                  "it; a float either way, so a restored state is checked alike")
_SCALES_FLOAT = ("step is called by the engine with its r_scale, a float64 array (np.ones(2), "
                 "then what step returned)")
_SLICE_END = "for b = 1 the slice 3:7 of a 6-vector is 3:6; for b = 0 both are 0:3"
EQUIVALENT.update({
    _SL + "_read_lines__mutmut_8": ('with open(path, encoding="utf-8", newline=None) as f:',
                                    _SPLITLINES),
    _SL + "_read_lines__mutmut_11": ('with open(path, encoding="utf-8", ) as f:', _SPLITLINES),
    _SL + "_read_lines__mutmut_13": ('with open(path, encoding="UTF-8", newline="") as f:',
                                     _CODEC),
    _SL + "_parse_rows__mutmut_26": ("return np.array(rows, dtype=None), np.array(numbers)",
                                     _FLOATS_LIST),
    _SL + "_parse_rows__mutmut_28": ("return np.array(rows, ), np.array(numbers)",
                                     _FLOATS_LIST),
    _SL + "__check_columns__mutmut_8": ("have = [c for c in group if c not in present]",
                                        _PARTLY),
    _SL + "_check_imu__mutmut_58": ('kind = "gap" if gap[k - 1] >= 0 else "overlap"',
                                    _NONZERO_GAP),
    _SL + "_check_overlap__mutmut_3": ("break", _LAST_FILE),
    _SL + "_read_log__mutmut_12": ("break", _LAST_FILE),
    _SL + "_check_log__mutmut_12": ("break", _LAST_FILE),
    _SL + "__write_table__mutmut_1": (
        "def _write_table(path: Path, data, origin=1.0) -> None:", _ORIGIN_PASSED),
    _SL + "__write_table__mutmut_12": (
        'with open(path, "w", encoding=None, newline="") as f:', _ASCII_TEXT),
    _SL + "__write_table__mutmut_16": ('with open(path, "w", newline="") as f:', _ASCII_TEXT),
    _SL + "__write_table__mutmut_21": (
        'with open(path, "w", encoding="UTF-8", newline="") as f:', _CODEC),
    _SL + "__write_table__mutmut_13": (
        'with open(path, "w", encoding="utf-8", newline=None) as f:', _LINESEP),
    _SL + "__write_table__mutmut_17": ('with open(path, "w", encoding="utf-8", ) as f:',
                                       _LINESEP),
    _SL + "_write_log__mutmut_10": (
        'parent = folder.parent if (str(folder.parent)) or True else Path(".")',
        _PARENT_NEVER_EMPTY),
    _SL + "_write_log__mutmut_11": (
        'parent = folder.parent if str(None) else Path(".")', _PARENT_NEVER_EMPTY),
    _SL + "_write_log__mutmut_12": (
        "parent = folder.parent if str(folder.parent) else Path(None)", _PARENT_NEVER_EMPTY),
    _SL + "_write_log__mutmut_13": (
        'parent = folder.parent if str(folder.parent) else Path("XX.XX")', _PARENT_NEVER_EMPTY),
    _SL + "__umask__mutmut_3": ("mask = os.umask(1)", _UMASK_RESTORED),
    _AHRS + "_triad_attitude__mutmut_3": ("f_b = np.asarray(f_b, dtype=None)", _FLOAT_INPUTS),
    _AHRS + "_triad_attitude__mutmut_5": ("f_b = np.asarray(f_b, )", _FLOAT_INPUTS),
    _AHRS + "_triad_attitude__mutmut_8": ("m_b = np.asarray(m_b, dtype=None)", _FLOAT_INPUTS),
    _AHRS + "_triad_attitude__mutmut_10": ("m_b = np.asarray(m_b, )", _FLOAT_INPUTS),
    _AHRS + "_triad_attitude__mutmut_25": (
        "if not (np.linalg.norm(f_b) >= 0 and n_east > 0):", _NAN_REFUSED),
    _AHRS + "__quat_multiply_rows__mutmut_35": (
        "w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2), axis=+1)", _LAST_AXIS),
    _AHRS + "__bias_quats__mutmut_22": ("safe = np.where(t >= 1e-6, t, 1.0)",
                                        _SERIES_STAND_IN),
    _AHRS + "__bias_quats__mutmut_24": ("safe = np.where(t > 1e-6, t, 2.0)",
                                        _SERIES_STAND_IN),
    _AHRS + "ǁUkfAhrsEngineǁ__init____mutmut_10": ("self.inclination = None", _NEVER_READ),
    _AHRS + "ǁUkfAhrsEngineǁ__init____mutmut_63": ("self.last_nis = 1.0", _NIS_SET_FIRST),
    _AHRS + "ǁUkfAhrsEngineǁaccumulate__mutmut_7": (
        "self.dq = _qmul(self.dq, _rotvec_quat(*np.asarray(dtheta, dtype=None).tolist()))",
        _FLOAT_INPUTS),
    _AHRS + "ǁUkfAhrsEngineǁaccumulate__mutmut_9": (
        "self.dq = _qmul(self.dq, _rotvec_quat(*np.asarray(dtheta, ).tolist()))",
        _FLOAT_INPUTS),
    _AHRS + "ǁUkfAhrsEngineǁupdate__mutmut_4": (
        "z = np.concatenate((np.asarray(f_b, None), np.asarray(m_b, float) / self.field_inte"
        "nsity))", _FLOAT_INPUTS),
    _AHRS + "ǁUkfAhrsEngineǁupdate__mutmut_6": (
        "z = np.concatenate((np.asarray(f_b, ), np.asarray(m_b, float) / self.field_intensity))",
        _FLOAT_INPUTS),
    _AHRS + "ǁUkfAhrsEngineǁupdate__mutmut_9": (
        "z = np.concatenate((np.asarray(f_b, float), np.asarray(m_b, None) / self.field_inte"
        "nsity))", _FLOAT_INPUTS),
    _AHRS + "ǁUkfAhrsEngineǁupdate__mutmut_11": (
        "z = np.concatenate((np.asarray(f_b, float), np.asarray(m_b, ) / self.field_intensity))",
        _FLOAT_INPUTS),
    _AHRS + "ǁFuzzyAdaptiveRǁstep__mutmut_26": ("new = np.array(r_scale, dtype=None)",
                                                _SCALES_FLOAT),
    _AHRS + "ǁFuzzyAdaptiveRǁstep__mutmut_28": ("new = np.array(r_scale, )", _SCALES_FLOAT),
    _AHRS + "ǁFuzzyAdaptiveRǁstep__mutmut_43": ("block = slice(3 * b, 4 * b + 3)", _SLICE_END),
    # Campaign summary, sweep and executor
    _SUMMARY + "_paper_values__mutmut_14": ("break", _MISSION_LAST),
    _SWEEP + "_run_point__mutmut_19": ("build=None, log=lambda m: None)", _DIRECT_ONLY),
    _SWEEP + "_run_point__mutmut_20": ("build=False, log=None)", _DIRECT_ONLY),
    _SWEEP + "_run_point__mutmut_26": ("log=lambda m: None)", _DIRECT_ONLY),
    _SWEEP + "_run_point__mutmut_27": ("build=False, )", _DIRECT_ONLY),
    _SWEEP + "_run_point__mutmut_30": ("build=True, log=lambda m: None)", _DIRECT_ONLY),
    _SWEEP + "_run_point__mutmut_31": ("build=False, log=lambda m: 0)", _DIRECT_ONLY),
    _SWEEP + "__mean_over_seeds__mutmut_14": (
        'return float(np.mean(values)) if values else float("NAN")', _NAN_SPELLING),
    _SWEEP + "_plot_sweep__mutmut_82": ("ax.grid(None, alpha=0.3)", _GRID_ON),
    _SWEEP + "_plot_sweep__mutmut_84": ("ax.grid(alpha=0.3)", _GRID_ON),
    # filter helpers and log converters
    "navcore.filters.array_checks.x_square__mutmut_23": (
        "if m is not None and a.shape[1] != m:", _SQUARE),
    "navcore.filters.nis_monitor.xǁNisMonitorǁ__init____mutmut_5": (
        "self.warned = None", "warned is only read by `if`: None is false as False is"),
    "navcore.filters.nis_monitor.xǁNisMonitorǁobserve__mutmut_2": (
        "if self.span < 0.0 or self.warned:", _ZERO_SPAN),
    # the exchange without test_master.py's CSV test
    _EXCH + "_step_order__mutmut_28": (
        "sub = [(a, b) for a, b, _ in active if a in rem or b in rem]", _NO_PATH_THROUGH_ORDERED),
    _EXCH + "_step_order__mutmut_50": ("delayed[id(c)] = None", _KEYS_ONLY),
    _EXCH + "ǁSlotǁcopy_inputs__mutmut_4": (
        'vectors[t].take(src, out=self.buffers[t], mode=None)', _IN_RANGE),
    _EXCH + "ǁSlotǁcopy_inputs__mutmut_7": (
        'vectors[t].take(src, out=self.buffers[t], )', _IN_RANGE),
    _EXCH + "ǁSlotǁcopy_inputs__mutmut_11": ("period = None", _UNIFORM_SHORTCUT),
    _EXCH + "ǁSlotǁcopy_inputs__mutmut_17": (
        'vectors[t].take(src, out=self.buffers[t], mode=None)', _IN_RANGE),
    _EXCH + "ǁSlotǁcopy_inputs__mutmut_20": (
        'vectors[t].take(src, out=self.buffers[t], )', _IN_RANGE),
    _EXCH + "_slots_for__mutmut_11": ("dtype=None)", _INT64),
    _EXCH + "_slots_for__mutmut_13": (")", _INT64),
    _EXCH + "_slots_for__mutmut_17": ("for v in inputs], dtype=None)", _INT64),
    _EXCH + "_slots_for__mutmut_19": ("for v in inputs], )", _INT64),
    _EXCH + "_exchange_for__mutmut_21": (
        "return GaussSeidel(slots, order, vectors, start, h, None, timing)", _GS_STEPS),
    _LC + "_read_plain_text__mutmut_19": (
        'text = line.split("#", )[0].replace(",", " ")', _COMMENT_SPLIT),
    _LC + "_read_plain_text__mutmut_22": (
        'text = line.split("#", 2)[0].replace(",", " ")', _COMMENT_SPLIT),
    _LC + "_read_plain_text__mutmut_58": (
        "return np.array(rows, dtype=None), np.array(numbers), tuple(names)", _PARSED_FLOATS),
    _LC + "_read_plain_text__mutmut_60": (
        "return np.array(rows, ), np.array(numbers), tuple(names)", _PARSED_FLOATS),
    _LC + "_trapezoid_increments__mutmut_3": ("time = np.asarray(time, dtype=None)", _FLOAT_RATES),
    _LC + "_trapezoid_increments__mutmut_5": ("time = np.asarray(time, )", _FLOAT_RATES),
    _LC + "_trapezoid_increments__mutmut_8": (
        "rates = np.asarray(rates, dtype=None)", _FLOAT_RATES),
    _LC + "_trapezoid_increments__mutmut_10": ("rates = np.asarray(rates, )", _FLOAT_RATES),
    _LC + "__refuse_local_frame__mutmut_13": (
        'first = lines[0].split(",")[0].strip() if lines else "XXXX"', _LOCAL_FRAME_DEFAULT),
    _LC + "_read_gnss_ins_sim__mutmut_199": (
        '"valid": (valid > 0.5).astype(None)}', _BOOL_AS_FLOAT),
    _LC + "_read_gnss_ins_sim__mutmut_326": ('imu["_line"] = np.arange(3, n + 3)', _EXTRA_LINE),
    _LC + "_read_gnss_ins_sim__mutmut_327": ('gnss["_line"] = None', _DEFAULT_LINE),
    _LC + "_read_gnss_ins_sim__mutmut_336": (
        'gnss["_line"] = np.arange(2, len(gps_time) + 3)', _EXTRA_LINE),
    _LC + "_read_gnss_ins_sim__mutmut_338": ('truth["_line"] = None', _DEFAULT_LINE),
    _LC + "_read_gnss_ins_sim__mutmut_347": (
        'truth["_line"] = np.arange(2, n + 3)', _EXTRA_LINE),
    _LC + "_read_gnss_ins_sim__mutmut_356": (
        'check_log(log, where=None, sources={IMU_FILE: d / "time.csv", GNSS_FILE: d / '
        '"gps_time.csv",', _NAMED_SOURCES),
    _LC + "_read_gnss_ins_sim__mutmut_359": (
        'check_log(log, sources={IMU_FILE: d / "time.csv", GNSS_FILE: d / "gps_time.csv",',
        _NAMED_SOURCES),
    _LC + "_read_gnss_ins_sim__mutmut_361": (
        'check_log(log, where=str(None), sources={IMU_FILE: d / "time.csv", GNSS_FILE: d / '
        '"gps_time.csv",', _NAMED_SOURCES),
    _LC + "__check_kf_gins_pair__mutmut_15": (
        'span = lambda t: float(t[-1] - t[0]) if (len(t) > 1) or True else 0.0',
        _ONE_SAMPLE_SPAN),
    _LC + "__check_kf_gins_pair__mutmut_21": (
        'span = lambda t: float(t[-1] - t[0]) if len(t) >= 1 else 0.0', _ONE_SAMPLE_SPAN),
    _LC + "__check_kf_gins_pair__mutmut_23": (
        'span = lambda t: float(t[-1] - t[0]) if len(t) > 1 else 1.0', _ONE_SAMPLE_SPAN),
    _INIT + "_coarse_alignment__mutmut_12": (
        "w_level = euler_to_dcm(roll, pitch, 0.0) @ np.asarray(w_body, dtype=None)",
        _FLOAT_PRODUCT),
    _INIT + "_coarse_alignment__mutmut_14": (
        "w_level = euler_to_dcm(roll, pitch, 0.0) @ np.asarray(w_body, )", _FLOAT_PRODUCT),
    _INIT + "_disagreement__mutmut_3": ("d = np.asarray(z_pos, dtype=None)[:3]", _FLOAT_PRODUCT),
    _INIT + "_disagreement__mutmut_5": ("d = np.asarray(z_pos, )[:3]", _FLOAT_PRODUCT),
    _INIT + "_disagreement__mutmut_11": (
        "sigma = np.sqrt(np.asarray(pos_var, dtype=None) + np.asarray(r_pos, dtype=float) ** 2)",
        _FLOAT_PRODUCT),
    _INIT + "_disagreement__mutmut_13": (
        "sigma = np.sqrt(np.asarray(pos_var, ) + np.asarray(r_pos, dtype=float) ** 2)",
        _FLOAT_PRODUCT),
    _INIT + "_disagreement__mutmut_16": (
        "sigma = np.sqrt(np.asarray(pos_var, dtype=float) + np.asarray(r_pos, dtype=None) ** 2)",
        _FLOAT_PRODUCT),
    _INIT + "_disagreement__mutmut_18": (
        "sigma = np.sqrt(np.asarray(pos_var, dtype=float) + np.asarray(r_pos, ) ** 2)",
        _FLOAT_PRODUCT),
    _INIT + "ǁInitializerǁ__init____mutmut_8": (
        "self.checked = None          # given: the first fix was compared with the state",
        "checked is only read by `if not`: None is false as False is"),
    _INIT + "ǁInitializerǁ__init____mutmut_10": (
        "self.warned = None           # ... and found too far from it (warned once)",
        _ONLY_WRITTEN),
    _INIT + "ǁInitializerǁ__init____mutmut_11": (
        "self.warned = True           # ... and found too far from it (warned once)",
        _ONLY_WRITTEN),
    _INIT + "ǁInitializerǁstate_from_fix__mutmut_38": (
        "roll, pitch = level(self.rest_dvel * self.rest_time)", _SCALE_FREE),
    _INIT + "ǁInitializerǁstate_from_alignment__mutmut_8": (
        "roll, pitch, yaw = coarse_alignment(self.all_dvel * self.elapsed,", _SCALE_FREE),
    _INIT + "ǁInitializerǁstate_from_alignment__mutmut_9": (
        "self.all_dtheta * self.elapsed)", _SCALE_FREE),
    _INIT + "ǁInitializerǁstart_sigmas__mutmut_24": (
        "v_sigma = (r_sigma[3:7] if len(r_sigma) == 6 else", _THREE_OR_SIX),
    _INIT + "ǁInitializerǁstart_sigmas__mutmut_32": (
        "math.sqrt(2.0) * r_sigma[0:4] / MAX_DIFFERENCED_FIX_GAP)", _THREE_OR_SIX),
})

# Co-simulation master
_MASTER = "orchestrator.cosim.master.x"
_SIM = _MASTER + "ǁSimulationǁ"
_CHECKS = "orchestrator.cosim.model_checks.xǁModelChecksǁ"
_LOOP = "orchestrator.cosim.macro_loop.xǁMacroLoopǁ"
_ASSEMBLY = "orchestrator.cosim.result_assembly.x"
_ASSEMBLE = _ASSEMBLY + "ǁResultAssemblyǁ"
_WHOLE_ROW = ("the whole-row copy is a shortcut: a type it no longer takes, or takes as well, "
              "is copied by take with the indices 0 .. n-1, the same values")
_INDEX_IN_RANGE = ("every index taken is a position of the vector (from _layout): take's mode, "
                   "'clip' or the default 'raise', never acts")
_NO_DOT = "str.partition gives an empty tail without a separator: var is '' when dot is"
_OFFSET_BY_ONE = ("every position, slice and vector size is shifted by the same one: element 0 "
                  "of each vector is never read or written, the exchange goes by index")
_POSITIONS_INT = ("the positions are Python ints: numpy makes an int64 array of them, which take "
                  "and int() read as the intp one; an empty one (float64) is only counted and "
                  "compared with an empty arange")
_ROW_COUNT = ("Recording takes int(n_rows): for fewer than 2**52 steps int(n / r + 1) is "
              "n // r + 1 exactly")
_NO_PROGRESS = ("without progress next_progress is only compared with k + 1 <= n_steps: n_steps "
                "+ 1 and + 2 are both never reached")
_ROW_NUMBERS = ("the row numbers are integers below 2**53: as int64 or float64 they give the "
                "same float64 times in the product")
_EMPTY_FLOAT = "np.empty's default dtype is float64"
_NAN_TEXT = "float() reads 'NAN' as 'nan' (case-insensitive)"
EQUIVALENT.update({
    _ASSEMBLY + "_row_recorder__mutmut_2": (
        "if np.array_equal(None, np.arange(len(vectors[t])))]", _WHOLE_ROW),
    _ASSEMBLY + "_row_recorder__mutmut_3": ("if np.array_equal(rec_index[t], None)]", _WHOLE_ROW),
    _ASSEMBLY + "_row_recorder__mutmut_8": (
        "picked = [t for t in NUMERIC_TYPES if t not in whole or len(rec_index[t])]", _WHOLE_ROW),
    _ASSEMBLY + "_row_recorder__mutmut_13": (
        "vectors[t].take(rec_index[t], out=recordings[t][row], mode=None)", _INDEX_IN_RANGE),
    _ASSEMBLY + "_row_recorder__mutmut_16": (
        "vectors[t].take(rec_index[t], out=recordings[t][row], )", _INDEX_IN_RANGE),
    _CHECKS + "_split__mutmut_7": ('return comp, var if (dot) or True else ""', _NO_DOT),
    _SIM + "_layout__mutmut_12": ("sizes = {t: 1 for t in NUMERIC_TYPES}", _OFFSET_BY_ONE),
    _SIM + "run__mutmut_15": ("dtype=None) for t in NUMERIC_TYPES}", _POSITIONS_INT),
    _SIM + "run__mutmut_17": (") for t in NUMERIC_TYPES}", _POSITIONS_INT),
    _SIM + "run__mutmut_33": ("recording = Recording(n_steps / self.record_every + 1,",
                              _ROW_COUNT),
    _LOOP + "_loop__mutmut_15": (
        "next_progress = progress_every if progress is not None else n_steps + 2", _NO_PROGRESS),
    _ASSEMBLE + "_chunk__mutmut_6": (
        "time_column = (self.model.start_time + (first_row + np.arange(n_rows, dtype=None))",
        _ROW_NUMBERS),
    _ASSEMBLE + "_chunk__mutmut_8": (
        "time_column = (self.model.start_time + (first_row + np.arange(n_rows, ))",
        _ROW_NUMBERS),
    _ASSEMBLE + "_chunk__mutmut_18": ("arr = np.empty((n_rows, len(names)), dtype=None)",
                                 _EMPTY_FLOAT),
    _ASSEMBLE + "_chunk__mutmut_20": ("arr = np.empty((n_rows, len(names)), )", _EMPTY_FLOAT),
    _ASSEMBLE + "_results__mutmut_27": (
        'step_time[n] = do_ns[i] / calls[i] * 1e-9 if calls[i] else float("NAN")', _NAN_TEXT),
    _ASSEMBLE + "_results__mutmut_36": (
        'exchange_time[n] = all_ns[i] / calls[i] * 1e-9 if calls[i] else float("NAN")',
        _NAN_TEXT),
})
