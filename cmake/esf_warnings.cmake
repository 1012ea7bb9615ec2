# Warnings per target, never global flags. ESF_WERROR (on in CI) turns them into errors.
function(esf_set_warnings target)
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                           $<$<BOOL:${ESF_WERROR}>:-Werror>)
endfunction()
