# bash completion for unav: source install/unav_cli/share/unav_cli/completion/unav.bash
_unav() {
  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[1]} sub=${COMP_WORDS[2]}
  case $COMP_CWORD in
    1) COMPREPLY=($(compgen -W "topic node launch bag eval datagen localize run foxglove security doctor" -- "$cur")) ;;
    2) case $prev in
         topic) COMPREPLY=($(compgen -W "list echo hz bw pub" -- "$cur")) ;;
         node) COMPREPLY=($(compgen -W "list" -- "$cur")) ;;
         eval) COMPREPLY=($(compgen -W "ape rpe" -- "$cur")) ;;
         bag) COMPREPLY=($(compgen -W "record play info" -- "$cur")) ;;
         launch) COMPREPLY=($(compgen -f -X '!*.launch.yaml' -- "$cur") $(compgen -d -- "$cur")) ;;
       esac ;;
    3) if [[ $prev == topic && $sub =~ ^(echo|hz|bw|pub)$ ]]; then
         COMPREPLY=($(compgen -W "$(UNAV_SPIN_TIME=0.5 unav topic list 2>/dev/null)" -- "$cur"))
       fi ;;
  esac
}
complete -o filenames -F _unav unav
