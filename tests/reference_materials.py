"""Published fits of the MERL materials (Ngan et al. 2005), mapped to brdffit's models.

Read from ``../shared/data/ngan2005/`` (the bbm project's tables; see its
README for the mapping); tests that need them skip where that folder is absent.
"""

import math
import re

from paths import NGAN_FOLDER

SKIP_REASON = f"reference data {NGAN_FOLDER} is absent (it ships beside the project, not in it)"

_FILES = {
    "ward": "ngan_ward.fit",
    "ward-duer": "ngan_wardduer.fit",
    "cook-torrance": "ngan_cooktorrance.fit",
    "lafortune": "ngan_lafortune.fit",
    "phong": "ngan_blinnphong.fit",
}
_LINE = re.compile(
    r"^(?P<name>[\w-]+) = Aggregate\(Lambertian\(albedo = (?P<diffuse>\[[^\]]*\])\), Ngan\w+\((?P<lobe>.*)\)\)$"
)
_FIELD = re.compile(r"(\w+) = (\[[^\]]*\]|[-\d.e+]+)")


def _number_or_list(text: str):
    if text.startswith("["):
        return [float(x) for x in text.strip("[]").split(",")]
    return float(text)


def ngan_materials(model: str) -> dict[str, dict]:
    """``{material: params}`` in brdffit's names and normalisation (docs/models.md)."""
    materials = {}
    for line in (NGAN_FOLDER / _FILES[model]).read_text().splitlines():
        match = _LINE.match(line.strip())
        if not match:
            continue
        fields = {key: _number_or_list(value) for key, value in _FIELD.findall(match["lobe"])}
        diffuse = _number_or_list(match["diffuse"])
        if model == "cook-torrance":
            params = {
                "kd": diffuse,
                "ks": [4.0 * a / math.pi for a in fields["albedo"]],
                "m": fields["roughness"],
                "f0": fields["eta"],
            }
        elif model == "lafortune":
            lobe = {"rho_s": fields["albedo"], "cxy": fields["Cxy"], "cz": fields["Cz"], "n": fields["sharpness"]}
            params = {"rho_d": diffuse, "lobes": [lobe]}
        elif model == "phong":
            params = {"rho_d": diffuse, "rho_s": fields["albedo"], "n": fields["sharpness"]}
        else:
            params = {"rho_d": diffuse, "rho_s": fields["albedo"], "alpha": fields["roughness"]}
        materials[match["name"]] = params
    return materials


def flat_parameters(params: dict, prefix: str = "") -> dict[str, float]:
    """``{"rho_d[0]": …, "alpha": …, "lobes[0].cxy": …}``: every number of a parameter dictionary by name."""
    flat = {}
    for key, value in params.items():
        if key == "lobes":
            for index, lobe in enumerate(value):
                flat.update(flat_parameters(lobe, f"{prefix}lobes[{index}]."))
        elif isinstance(value, list):
            flat.update({f"{prefix}{key}[{c}]": float(x) for c, x in enumerate(value)})
        else:
            flat[prefix + key] = float(value)
    return flat
