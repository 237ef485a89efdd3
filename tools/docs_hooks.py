"""MkDocs hooks of the docs site (``mkdocs.yml``: ``hooks``): the pages made from the code.

- ``envs/``: one page per registered env id, from its class docstring (Gymnasium's env-page
  layout: the docstring is the spec), with the facts of the registration and of a made env
  (spaces, step limit, batched form, the vessels that fit the task);
- ``vessels/``: one page per packaged vessel, its package README under its rendered image
  (``tools/render_vessels.py``) and a table of its data; ``vessels/format.md``: the package
  format;
- ``cli-reference.md``: every ``shipgym`` command's ``--help``, from the parser;
- ``api/``: one page per public module, rendered by mkdocstrings from its docstrings;
- the navigation, with these pages and the design notes in ``docs/design/``.

Nothing is written into ``docs/``: the pages exist in the build only.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import pkgutil
import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

#: the hand-written pages, in the order of the navigation (generated sections slot in)
NAV_HEAD: list[Any] = [
    {"Home": "index.md"},
    {"Getting started": "getting-started.md"},
    {
        "Tutorials": [
            {"A harbour episode": "tutorials/harbour-episode.md"},
            {"Benchmarking observers": "tutorials/observers.md"},
            {"Training PPO": "tutorials/train-ppo.md"},
            {"Recording and viewing headless": "tutorials/recording.md"},
            {"Writing a vessel package": "tutorials/vessel-package.md"},
        ]
    },
    {"Many envs at once": "batched.md"},
]
NAV_TAIL: list[Any] = [
    {
        "Models": [
            {"Overview": "models/index.md"},
            {"Hull": "models/hull.md"},
            {"Actuators and allocation": "models/actuators.md"},
            {"Wind": "models/wind.md"},
            {"Waves": "models/waves.md"},
            {"Current": "models/current.md"},
            {"Sensors": "models/sensors.md"},
            {"Command conditioning": "models/conditioning.md"},
        ]
    },
    {
        "Papers reproduced": [
            {"Tomera (2014): the Blue Lady": "papers/tomera-2014.md"},
            {"Tomera (2011): Kalman-Bucy filter design": "papers/tomera-2011.md"},
            {"Al-Takie (1982): offshore DP": "papers/al-takie-1982.md"},
            {"Radhakrishnan: rudder-roll": "papers/radhakrishnan.md"},
            {"Artyszuk (2003): sea trials": "papers/artyszuk-2003.md"},
        ]
    },
    {"Learned baselines": "baselines.md"},
    {"Speed": "speed.md"},
]


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")


def env_pages() -> dict[str, str]:
    """``envs/<slug>.md`` -> its markdown, one per registered id, and ``envs/index.md``."""
    import gymnasium as gym

    import shipgym
    from shipgym.dynamics import vessels
    from shipgym.envs.base import ShipEnv
    from shipgym.envs.registration import ALIASES, ENV_IDS, VECTOR_IDS, task_fits_vessel
    from shipgym.envs.scene import fits

    pages: dict[str, str] = {}
    rows = []
    all_vessels = vessels()
    for env_id in ENV_IDS:
        spec = gym.spec(env_id)
        module, _, name = str(spec.entry_point).partition(":")
        cls = getattr(importlib.import_module(module), name)
        first = (inspect.getdoc(cls) or "").split("\n\n")[0].replace("\n", " ")
        harbour = "Harbour" in env_id  # the basin was built for the Blue Lady
        fit = [v for v, ves in all_vessels.items() if task_fits_vessel(env_id, ves)
               and (not harbour or fits(ves, "harbour"))]  # fmt: skip
        required = False
        try:  # the task's own default vessel, else the first that fits (the Blue Lady first)
            env = shipgym.make(env_id)
        except TypeError:  # the vessel-neutral ids need vessel=
            required = True
            fit.sort(key=lambda v: v != "blue-lady")
            env = shipgym.make(env_id, vessel=fit[0])
        try:
            act, obs = env.action_space, env.observation_space
            u = env.unwrapped  # a plan task's vessel, or a stepped task's base vessel
            vessel = getattr(getattr(u, "vessel", None) or getattr(u, "base_vessel", None),
                             "name", "-")  # fmt: skip
        finally:
            env.close()
        vessel_fact = (f"none: `vessel=` is required (the spaces above are `{vessel}`'s)"
                       if required else f"`{vessel}`")  # fmt: skip
        slug = _slug(env_id.removeprefix("shipgym/"))
        rows.append(f"| [`{env_id}`]({slug}.md) | {first} |")
        alias = ALIASES.get(env_id)
        facts = [
            ("Import", f'`gymnasium.make("{env_id}")` after `import shipgym`'),
            (
                "Batched",
                f'`gymnasium.make_vec("{env_id}", num_envs=N)`' if env_id in VECTOR_IDS else "no",
            ),  # fmt: skip
            ("Class", f"`{module}.{name}`"),
            ("Action space", f"`{act}`"),
            ("Observation space", f"`{obs}`"),
            (
                "Step limit",
                f"{spec.max_episode_steps} control steps"
                if spec.max_episode_steps
                else "the task's own (`episode_duration`)",
            ),  # fmt: skip
            ("Default vessel", vessel_fact),
            ("Vessels that fit", ", ".join(f"[`{v}`](../vessels/{v}.md)" for v in fit)),
        ]
        if alias:
            facts.append(("Alias of", f'`{alias}` with `vessel="blue-lady"`'))
        table = "\n".join(["| | |", "|---|---|", *(f"| {k} | {v} |" for k, v in facts)])
        pages[f"envs/{slug}.md"] = (
            f"# {env_id}\n\n{table}\n\n"
            "The action space comes from the vessel's actuators: another vessel has its own.\n\n"
            f"::: {module}.{name}\n"
            "    options:\n      show_root_heading: false\n      members: false\n"
            "      show_bases: true\n"
        )
        if issubclass(cls, ShipEnv) and cls is not ShipEnv:  # its spaces, reward, info
            pages[f"envs/{slug}.md"] += (
                "\n## Spaces, reward, termination and info (`ShipEnv`)\n\n"
                "::: shipgym.envs.base.ShipEnv\n"
                "    options:\n      show_root_heading: false\n      members: false\n"
            )
    pages["envs/index.md"] = (
        "# Environments\n\nEvery id is registered by `import shipgym` and has a native batched "
        "form (`gymnasium.make_vec(id, num_envs=N)`, see [Many envs at once](../batched.md)). "
        "Each page is made from the env's class docstring, which is its spec.\n\n"
        "| id | task |\n|---|---|\n" + "\n".join(rows) + "\n"
    )
    return pages


def vessel_pages() -> dict[str, str]:
    """``vessels/<name>.md`` -> its markdown, one per packaged vessel, and the format page."""
    from shipgym.dynamics import vessels

    pages: dict[str, str] = {}
    for name, v in sorted(vessels().items()):
        readme = (Path(v.folder) / "README.md").read_text()
        body = re.sub(r"^# .*\n", "", readme, count=1)
        title = re.match(r"# (.*)", readme)
        acts = ", ".join(f"`{c}`" for c in v.actuators.channel_names)
        facts = [
            ("Name", f'`{name}` (`shipgym.dynamics.load_vessel("{name}")`)'),
            ("Degrees of freedom", f"{v.dofs}"),
            ("Length overall, beam", f"{v.L_oa:g} m, {v.B:g} m"),
            ("Action channels", acts),
            ("Package", f"`shipgym/assets/mjcf/{Path(v.folder).name}/`"),
        ]
        table = "\n".join(["| | |", "|---|---|", *(f"| {k} | {val} |" for k, val in facts)])
        pages[f"vessels/{name}.md"] = (
            f"# {title.group(1) if title else name}\n\n![{name}]({name}.png)\n\n{table}\n\n"
            f"{_demote(body)}\n"
        )
    fmt = (ROOT / "shipgym" / "assets" / "mjcf" / "README.md").read_text()
    pages["vessels/format.md"] = fmt
    return pages


def _demote(md: str) -> str:
    """``md`` with its headings one level down, so that they nest under the page title."""
    out, fence = [], False
    for line in md.splitlines():
        if line.startswith("```"):
            fence = not fence
        if not fence and re.match(r"#+ ", line):
            line = "#" + line
        out.append(line)
    return "\n".join(out)


def cli_page() -> str:
    """``cli-reference.md``: every command's ``--help``, from the parser."""
    from shipgym.cli import _parser

    def walk(p: argparse.ArgumentParser, path: list[str]) -> list[str]:
        out = [f"{'#' * min(len(path) + 1, 4)} `{' '.join(path)}`\n",
               "```text\n" + p.format_help().rstrip() + "\n```\n"]  # fmt: skip
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    out += walk(child, [*path, name])
        return out

    parts = walk(_parser(), ["shipgym"])
    parts[0] = "# CLI reference\n\nMade from the `shipgym` parser: each command's `--help`.\n"
    return "\n".join(parts)


def api_modules() -> list[str]:
    """The public modules of the package (no part of the dotted name private)."""
    import shipgym

    names = ["shipgym"]
    for m in pkgutil.walk_packages(shipgym.__path__, "shipgym."):
        if not any(part.startswith("_") for part in m.name.split(".")):
            names.append(m.name)
    return sorted(names)


def api_pages() -> dict[str, str]:
    pages = {}
    for mod in api_modules():
        pages[f"api/{mod}.md"] = f"# `{mod}`\n\n::: {mod}\n"
    pages["api/index.md"] = (
        "# API reference\n\nOne page per public module, from its docstrings.\n\n"
        + "\n".join(f"- [`{m}`]({m}.md)" for m in api_modules())
        + "\n"
    )
    return pages


def design_nav() -> list[Any]:
    return [{"Design notes": "design/README.md"}] + [
        {p.stem: f"design/{p.name}"}
        for p in sorted((DOCS / "design").glob("*.md"))
        if p.name != "README.md"
    ]


_PAGES: dict[str, str] = {}


def on_config(config: Any) -> Any:
    _PAGES.clear()
    _PAGES.update(env_pages())
    _PAGES.update(vessel_pages())
    _PAGES["cli-reference.md"] = cli_page()
    _PAGES.update(api_pages())
    from shipgym.envs.registration import ENV_IDS

    envs = [{"Environments": "envs/index.md"}] + [
        {env_id.removeprefix("shipgym/"): f"envs/{_slug(env_id.removeprefix('shipgym/'))}.md"}
        for env_id in ENV_IDS
    ]
    ves = [{"Vessels": "vessels/index.md"}, {"Package format": "vessels/format.md"}] + [
        {p.removeprefix("vessels/").removesuffix(".md"): p}
        for p in _PAGES
        if p.startswith("vessels/") and p != "vessels/format.md"
    ]
    api = [{"API reference": "api/index.md"}] + [{m: f"api/{m}.md"} for m in api_modules()]
    config["nav"] = [
        *NAV_HEAD,
        {"Environments": envs},
        {"Vessels": ves},
        *NAV_TAIL,
        {"Command line": [{"Overview": "cli.md"}, {"Reference": "cli-reference.md"}]},
        {"API": api},
        {"Design notes": design_nav()},
        {"Development": "development.md"},
        {"References": "references.md"},
    ]
    return config


def on_files(files: Any, config: Any) -> Any:
    from mkdocs.structure.files import File

    for uri, content in _PAGES.items():
        files.append(File.generated(config, uri, content=content))
    return files


_ROLE = re.compile(
    r":(?:py:)?(?:meth|func|class|data|attr|mod|exc|obj|const):<code>(~?)([^<]*?)</code>"
)
_TARGET = re.compile(r"(?P<label>.*?) &lt;(?P<target>[\w.]+)&gt;$")


def _role_link(m: re.Match[str], module: str | None) -> str:
    """A docstring's Sphinx role (``:func:`name```, ``:class:`~a.B```, ``:meth:`label
    <a.B.c>```) as an optional cross-reference: a link where the name resolves (a fully
    qualified name, or one of the page's module), plain code where it does not."""
    short, text = m.group(1) == "~", m.group(2).removesuffix("()")
    target = _TARGET.match(text)
    ident, title = (target["target"], target["label"]) if target else (text, text)
    if short and not target:
        title = ident.rsplit(".", 1)[-1]
    if not ident.startswith("shipgym") and module is not None:
        ident = f"{module}.{ident}"  # a name of the page's own module
    return f'<autoref identifier="{ident}" optional><code>{title}</code></autoref>'


def on_page_content(html: str, page: Any, **_: Any) -> str:
    """The docstrings' Sphinx roles as optional cross-references (:func:`_role_link`)."""
    uri = page.file.src_uri
    module = uri[len("api/") : -len(".md")] if uri.startswith("api/") else None
    return _ROLE.sub(lambda m: _role_link(m, module), html)
