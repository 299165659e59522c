"""A catalogue of models with realistic parameters, fed to ``pytest.mark.parametrize``.

Each case is ``(model, options, params)``; the ids name the model and its options.
Parameters are of real materials (Ngan et al. 2005's fits) or textbook values.
"""

import pytest


def gltf_params(
    roughness,
    metallic,
    *,
    base_color,
    ior=1.5,
    clearcoat=0.0,
    clearcoat_roughness=0.0,
    strength=0.0,
    rotation=0.0,
    sheen_color=None,
    sheen_roughness=0.0,
) -> dict:
    """The ``gltf`` model's parameters in its order (a result file's), its held ones at their defaults unless given;
    with a ``sheen_color``, those of ``gltf:sheen=true``."""
    params = {
        "roughness": roughness,
        "metallic": metallic,
        "ior": ior,
        "clearcoat": clearcoat,
        "clearcoat_roughness": clearcoat_roughness,
        "anisotropy_strength": strength,
        "anisotropy_rotation": rotation,
    }
    if sheen_color is None:
        return params | {"base_color": base_color}
    sheen_color = sheen_color if isinstance(sheen_color, list) else [sheen_color] * len(base_color)
    return params | {"sheen_roughness": sheen_roughness, "base_color": base_color, "sheen_color": sheen_color}


CASES = [
    ("lambert", {}, {"rho_d": [0.5, 0.3, 0.2]}),
    ("ward", {}, {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146}),
    ("ward-aniso", {}, {"rho_d": [0.1, 0.1, 0.1], "rho_s": [0.05, 0.04, 0.03], "alpha_x": 0.08, "alpha_y": 0.25}),
    ("ward-duer", {}, {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.025, 0.022, 0.015], "alpha": 0.146}),
    (
        "cook-torrance",
        {"fresnel": "schlick"},
        {"kd": [0.3, 0.26, 0.18], "ks": [0.41, 0.35, 0.23], "m": 0.139, "f0": 0.0203},
    ),
    (
        "cook-torrance",
        {"fresnel": "dielectric"},
        {"kd": [0.3, 0.26, 0.18], "ks": [0.41, 0.35, 0.23], "m": 0.139, "eta": 1.5},
    ),
    (
        "cook-torrance",
        {"fresnel": "conductor"},  # copper-like: an index per channel, ks 1 (held there by default)
        {"kd": [0.01, 0.01, 0.01], "ks": [1.0, 1.0, 1.0], "m": 0.2, "eta": [0.2, 0.92, 1.1], "k": [3.9, 2.45, 2.14]},
    ),
    ("cook-torrance", {"fresnel": "none"}, {"kd": [0.3, 0.26, 0.18], "ks": [0.05, 0.04, 0.03], "m": 0.25}),
    ("blinn-phong", {}, {"rho_d": [0.2, 0.1, 0.05], "rho_s": [0.05, 0.05, 0.05], "n": 60.0}),
    ("phong", {}, {"rho_d": [0.0432, 0.0167, 0.00699], "rho_s": [0.0092, 0.00786, 0.00539], "n": 82.1}),
    (
        "lafortune",
        {"lobes": 1},
        {
            "rho_d": [0.151, 0.101, 0.0591],
            "lobes": [{"rho_s": [0.151, 0.132, 0.0906], "cxy": -0.595, "cz": 0.541, "n": 46.8}],
        },
    ),
    (
        "lafortune",
        {"lobes": 2},
        {
            "rho_d": [0.1, 0.1, 0.1],
            "lobes": [
                {"rho_s": [0.1, 0.08, 0.06], "cxy": -0.62, "cz": 0.48, "n": 30.0},
                {"rho_s": [0.05, 0.05, 0.05], "cxy": 0.6, "cz": 0.529, "n": 8.0},
            ],
        },
    ),
    (  # a renderer's metal: GGX with separable Smith (Mitsuba's roughconductor), Mitsuba's gold (metals.py)
        "cook-torrance",
        {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"},
        {
            "kd": [0.01, 0.01, 0.01],
            "ks": [1.0, 1.0, 1.0],
            "m": 0.15,
            "eta": [0.143, 0.375, 1.442],
            "k": [3.98, 2.39, 1.6],
        },
    ),
    (  # a plastic: Beckmann with height-correlated Smith
        "cook-torrance",
        {"fresnel": "dielectric", "distribution": "beckmann", "shadowing": "smith-correlated"},
        {"kd": [0.3, 0.26, 0.18], "ks": [0.41, 0.35, 0.23], "m": 0.2, "eta": 1.5},
    ),
    (  # brushed gold: anisotropic GGX with separable Smith (Mitsuba's roughconductor with alpha_u, alpha_v)
        "cook-torrance",
        {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith", "anisotropic": True},
        {
            "kd": [0.01, 0.01, 0.01],
            "ks": [1.0, 1.0, 1.0],  # a conductor's ks is held at 1: its index, per channel, colours it
            "alpha_u": 0.08,
            "alpha_v": 0.3,
            "phi_t": 30.0,
            "eta": [0.15, 0.37, 1.44],
            "k": [4.0, 2.4, 1.6],
        },
    ),
    (  # a brushed lacquer: anisotropic Beckmann with height-correlated Smith, tangent at -60°
        "cook-torrance",
        {"fresnel": "dielectric", "distribution": "beckmann", "shadowing": "smith-correlated", "anisotropic": True},
        {
            "kd": [0.3, 0.26, 0.18],
            "ks": [0.41, 0.35, 0.23],
            "alpha_u": 0.1,
            "alpha_v": 0.25,
            "phi_t": -60.0,
            "eta": 1.5,
        },
    ),
    # glTF's own material (a whole-lobe model: no albedos beside it): a red paint under a glossy clear coat, and a
    # copper with a little dielectric under a strong, glossier one (a car paint); ior is held at glTF's 1.5 and the
    # anisotropy at 0 unless freed (tests/export/test_gltf_model.py frees them)
    ("gltf", {}, gltf_params(0.35, 0.0, clearcoat=0.5, clearcoat_roughness=0.1, base_color=[0.6, 0.2, 0.05])),
    ("gltf", {}, gltf_params(0.3, 0.9, clearcoat=0.8, clearcoat_roughness=0.15, base_color=[0.95, 0.64, 0.54])),
    # a velvet: a tinted sheen (KHR_materials_sheen, the option sheen) over a rough red dielectric
    (
        "gltf",
        {"sheen": True},
        gltf_params(0.8, 0.0, base_color=[0.5, 0.1, 0.15], sheen_color=[0.5, 0.45, 0.4], sheen_roughness=0.5),
    ),
    (  # Mitsuba's principled (a whole-lobe model): a blue paint under a clear coat; tints, sheen, anisotropy held at 0
        "principled",
        {},
        {
            "roughness": 0.45,
            "metallic": 0.0,
            "specular": 0.5,
            "spec_tint": 0.0,
            "anisotropic": 0.0,
            "sheen": 0.0,
            "sheen_tint": 0.0,
            "clearcoat": 0.3,
            "clearcoat_gloss": 0.7,
            "base_color": [0.2, 0.3, 0.6],
        },
    ),
    (  # Mitsuba's roughplastic (a whole-lobe model): a red plastic under a GGX coating of index 1.6
        "roughplastic",
        {"distribution": "ggx", "int_ior": 1.6},
        {"alpha": 0.15, "diffuse_reflectance": [0.8, 0.3, 0.1], "specular_reflectance": [1.0, 1.0, 1.0]},
    ),
]


def reciprocal(case) -> bool:
    """Whether the case's BRDF is reciprocal, ``f(wi, wo) = f(wo, wi)``: every model's but glTF's under a clear coat,
    which KHR_materials_clearcoat weights by Schlick's Fresnel term of the viewer's direction alone
    (``tests/export/test_gltf.py`` measures by how much). glTF's sheen is reciprocal: its albedo scaling takes the
    smaller of the viewer's and the light's (``tests/export/test_gltf_sheen.py``)."""
    model, _, params = case
    return not (model == "gltf" and params["clearcoat"] > 0)


#: The cases whose BRDF is reciprocal (:func:`reciprocal`), for the tests of reciprocity.
RECIPROCAL_CASES = [case for case in CASES if reciprocal(case)]


def anisotropic(case) -> bool:
    """Whether the case's BRDF may change when both directions turn about the normal: ``ward-aniso``'s, an
    anisotropic Cook-Torrance's, glTF's with an anisotropy strength, principled's with an ``anisotropic`` above 0."""
    model, options, params = case
    stretch = params.get("anisotropy_strength", 0) > 0 or params.get("anisotropic", 0) > 0
    return model == "ward-aniso" or bool(options.get("anisotropic")) or stretch


def case_id(case) -> str:
    model, options, params = case
    name = model + "".join(f"-{key if value is True else value}" for key, value in options.items())
    return name + ("-metal" if params.get("metallic", 0.0) > 0.5 else "")


#: The cases a per-case test runs in ``make test``, one of each kind: the diffuse model, Ward isotropic and
#: anisotropic, Cook-Torrance with Beckmann, V-groove and Schlick, a renderer's metal (GGX, Smith, a complex index),
#: one Lafortune lobe. The others (the variants of these, and the renderers' whole-lobe models, the costliest to
#: compile: glTF's, principled, roughplastic, ~10–30 s a test) are marked ``slow``: ``make test-slow``, which CI runs
#: too. In ``make test`` the export tests still fit glTF's material and check its exact export; principled's and
#: roughplastic's fits are in ``make test-slow`` alone.
QUICK_CASES = {
    "lambert",
    "ward",
    "ward-aniso",
    "cook-torrance-schlick",
    "cook-torrance-conductor-ggx-smith",
    "lafortune-1",
}


def case_params(cases=CASES, *, as_one: bool = False) -> list:
    """``pytest.param`` of each case (its three parts, or the case as one argument with ``as_one``), named by
    :func:`case_id`, marked ``slow`` outside :data:`QUICK_CASES`."""
    return [
        pytest.param(
            *([case] if as_one else case),
            id=case_id(case),
            marks=() if case_id(case) in QUICK_CASES else pytest.mark.slow,
        )
        for case in cases
    ]


def parametrize_cases(cases=CASES):
    """The test once per case, as ``(model, options, params)``: :func:`case_params`."""
    return pytest.mark.parametrize(("model", "options", "params"), case_params(cases))
