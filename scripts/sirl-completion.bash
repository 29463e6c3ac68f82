# Bash completion for `sirl`: commands, `sirl study` subcommands, the bundled profiles where a
# profile goes, options from `sirl CMD --help`, files elsewhere. Installed to
# share/bash-completion/completions/sirl (bash-completion loads it on first use); from a checkout:
#   source scripts/sirl-completion.bash
_sirl() {
  local cur prev cmd
  cur="${COMP_WORDS[COMP_CWORD]}"
  prev="${COMP_WORDS[COMP_CWORD-1]}"
  cmd="${COMP_WORDS[1]}"
  local commands="reproduce run plan evaluate dataset show export inspect render study submit status merge gc version"
  if [ "$COMP_CWORD" -eq 1 ]; then
    COMPREPLY=($(compgen -W "$commands --help --version" -- "$cur"))
    return
  fi
  if [ "$cmd" = study ] && [ "$COMP_CWORD" -eq 2 ]; then
    COMPREPLY=($(compgen -W "serve import simulate analyze merge" -- "$cur"))
    return
  fi
  if [[ "$cur" == -* ]]; then
    # The options `sirl CMD --help` lists (the command itself answers: never out of date).
    local words=("${COMP_WORDS[@]:1:COMP_CWORD-1}") opts
    opts=$("${COMP_WORDS[0]}" "${words[@]}" --help 2>/dev/null | grep -o -- '--[a-z][a-z0-9-]*' | sort -u)
    COMPREPLY=($(compgen -W "$opts" -- "$cur"))
    return
  fi
  # A profile: after --profile, or as the first argument of the commands that take one.
  if [ "$prev" = --profile ] || { [ "$COMP_CWORD" -eq 2 ] && [[ " reproduce run plan submit " == *" $cmd "* ]]; }; then
    local names
    names=$("${COMP_WORDS[0]}" plan --help 2>/dev/null | sed -n 's/.*a name in configs\/ (\([^)]*\)).*/\1/p' | head -1 | tr -d ',')
    COMPREPLY=($(compgen -W "$names" -- "$cur") $(compgen -f -X '!*.toml' -- "$cur") $(compgen -d -- "$cur"))
    return
  fi
  COMPREPLY=($(compgen -f -- "$cur"))
}
complete -o filenames -F _sirl sirl
