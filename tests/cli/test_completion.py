"""``rgraph completion``: the generated bash script completes commands, options and choices
(run through bash's own completion machinery), and zsh/fish scripts are generated."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

RGRAPH = [sys.executable, "-m", "rgraph"]


def script(shell: str) -> str:
    run = subprocess.run([*RGRAPH, "completion", shell], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return run.stdout


def complete(words: list[str], tmp_path) -> list[str]:
    path = tmp_path / "rgraph.bash"
    path.write_text(script("bash"))
    line = " ".join(f"'{w}'" for w in words)
    probe = (f"source {path}; COMP_WORDS=({line}); COMP_CWORD={len(words) - 1}; "
             "$(complete -p rgraph | sed -E 's/.*-F ([^ ]+) .*/\\1/'); printf '%s\\n' \"${COMPREPLY[@]}\"")
    run = subprocess.run(["bash", "-c", probe], capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert run.returncode == 0, run.stderr
    return [w for w in run.stdout.splitlines() if w]


@pytest.mark.skipif(shutil.which("bash") is None, reason="no bash")
def test_bash_completes_commands_options_choices_and_graphs(tmp_path):
    assert complete(["rgraph", "ins"], tmp_path) == ["inspect"]
    assert "completion" in complete(["rgraph", ""], tmp_path)
    assert complete(["rgraph", "run", "surgery", "--val"], tmp_path) == ["--validate"]
    assert complete(["rgraph", "run", "surgery", "--sync", ""], tmp_path) == ["normal", "naive"]
    assert complete(["rgraph", "completion", "z"], tmp_path) == ["zsh"]
    assert "surgery" in complete(["rgraph", "compile", "sur"], tmp_path)
    (tmp_path / "mygraph.yaml").write_text("rgraph: 1\n")
    assert complete(["rgraph", "validate", "mygr"], tmp_path) == ["mygraph.yaml"]


def test_zsh_and_fish_scripts():
    zsh = script("zsh")
    assert zsh.startswith("#compdef rgraph\n") and "bashcompinit" in zsh and "complete -o filenames -F _rgraph rgraph" in zsh
    fish = script("fish")
    assert "complete -c rgraph -n __fish_use_subcommand -a inspect" in fish
    assert "complete -c rgraph -n '__fish_seen_subcommand_from run' -l sync -x -a 'normal naive'" in fish
