!> The text of a namelist input, read as a person wrote it: groups, keys and values with the
!> line each is on. It checks an input against a schema (the groups, their keys and each key's
!> type) before the compiler's namelist reader sees it, so that a mistake is reported as
!> `file:line: &group: ...` with the valid keys and a "did you mean" (every unknown key of the
!> input at once, each with the nearest key or, for another name of a key such as a symbol of
!> the paper, the key it stands for), and it applies command
!> line overrides (`group.key=value`) to the text, so that the file's echo of the input is the
!> input actually run. Infrastructure, no model section.
!>
!> The syntax understood is the namelist syntax of the inputs: `&group`, then `key = values`
!> (values separated by commas or blanks, `r*value` repeats, quoted strings, `key(i)`
!> subscripts), `!` comments, and `/` (or `&end`) closing the group. Text outside groups is
!> ignored, as the compiler's reader ignores it.
module chain_namelist
    use, intrinsic :: iso_fortran_env, only: int64
    use chain_error, only: error_t, set_error, fmt_int, fmt_int8
    use chain_namelist_text, only: token_t, given_t, item_t, parsed_t, parse, given_items, &
                                   groups_in, same_input, lower, repeats, without_repeat, &
                                   is_integer, is_number, is_logical, after_separator
    implicit none
    private
    public :: key_spec_t, key_integer, key_real, key_logical, key_string, alias_t
    public :: check_namelist, apply_override, schema_keys, groups_in, lower, same_input
    public :: token_t, given_t, given_items

    integer, parameter :: key_integer = 1
    integer, parameter :: key_real = 2
    integer, parameter :: key_logical = 3
    integer, parameter :: key_string = 4
    character(len=*), parameter :: type_names(4) = &
        [character(len=16) :: 'an integer', 'a number', 'a logical', 'a string']

    !> One key of the schema: its group, its name, its type, whether it takes a list, and for
    !> an integer whether it is read into 64 bits (`wide`) rather than 32.
    type :: key_spec_t
        character(len=16) :: group = ''
        character(len=16) :: name = ''
        integer :: kind = key_real
        logical :: list = .false.
        logical :: wide = .false.
        integer :: most = huge(1)  !! the most values a list takes (the reader's array)
    end type key_spec_t

    !> Another name a person may write for a key, such as a symbol of the paper: never read
    !> as the key (the reader would then take a mistake for a value), only named in the
    !> message that refuses it. Keys are case-blind, so two symbols that differ only in case
    !> (`A` and `a`) are one name: the message names every key it may stand for.
    type :: alias_t
        character(len=16) :: group = ''
        character(len=16) :: symbol = ''  !! as it is written where it comes from (case kept)
        character(len=16) :: key = ''     !! the key of `group` it stands for
        character(len=48) :: meaning = '' !! what it stands for, for the message: "the ..."
    end type alias_t

contains

    !> Every group known, none twice, every one closed; every key of its group, with values of
    !> its type (one value unless it takes a list). `source` names the text in messages;
    !> `aliases`, other names of keys that the message for an unknown key names.
    subroutine check_namelist(source, text, schema, err, aliases)
        character(len=*), intent(in) :: source, text
        type(key_spec_t), intent(in) :: schema(:)
        type(error_t), allocatable, intent(out) :: err
        type(alias_t), intent(in), optional :: aliases(:)
        type(parsed_t) :: parsed
        integer :: g, j, i

        call parse(text, parsed)
        if (parsed%stray_first > 0) then
            call set_error(err, at(source, parsed%stray_line)//"'"// &
                           text(parsed%stray_first:parsed%stray_last)//"' is outside any "// &
                           "group; only '&group key = value ... /' is read (start a "// &
                           "comment with '!')")
            return
        end if
        do g = 1, size(parsed%groups)
            associate (group => parsed%groups(g))
                if (.not. any(schema%group == group%name)) then
                    call set_error(err, at(source, group%line)//"unknown group &"// &
                                   group%name//suggestion(group%name, group_names(schema), '&')// &
                                   ". The groups are "//listed(group_names(schema), '&'))
                    return
                end if
                do j = 1, g - 1
                    if (parsed%groups(j)%name == group%name) then
                        call set_error(err, at(source, group%line)//"group &"//group%name// &
                                       " appears more than once (first at line "// &
                                       fmt_int(parsed%groups(j)%line)//")")
                        return
                    end if
                end do
                if (group%close == 0) then
                    call set_error(err, at(source, group%line)//"&"//group%name// &
                                   ": the group has no closing '/'")
                    return
                end if
            end associate
        end do
        if (parsed%loose_first > 0) then
            call set_error(err, at(source, parsed%loose_line)//"&"//parsed%loose_group// &
                           ": '"//text(parsed%loose_first:parsed%loose_last)//"' is not a "// &
                           "value of any key (write key = value)")
            return
        end if
        call check_keys(source, parsed, schema, err, aliases)
        if (allocated(err)) return
        do j = 1, size(parsed%items)
            associate (item => parsed%items(j))
                do i = 1, j - 1
                    if (parsed%items(i)%group == item%group .and. &
                        lower(parsed%items(i)%written) == lower(item%written)) then
                        call set_error(err, at(source, item%line)//"&"//item%group//": "// &
                                       lower(item%written)//" is given twice (first at "// &
                                       "line "//fmt_int(parsed%items(i)%line)//"); give "// &
                                       "each key once")
                        return
                    end if
                end do
                if (item%comment_first) then
                    call set_error(err, at(source, item%line)//"&"//item%group//": "// &
                                   item%written//" = is followed by a comment before its "// &
                                   "value, which the namelist reader cannot read; put the "// &
                                   "comment after the value")
                    return
                end if
            end associate
            call check_item(at(source, parsed%items(j)%line)//"&"//parsed%items(j)%group// &
                            ": ", text, parsed%items(j), schema, err)
            if (allocated(err)) return
        end do
    end subroutine check_namelist

    !> Every item's key is a key of its group; else every unknown key is named, each on its
    !> line with its "did you mean", then the keys of each group concerned (one unknown key:
    !> one line, as the other messages).
    subroutine check_keys(source, parsed, schema, err, aliases)
        character(len=*), intent(in) :: source
        type(parsed_t), intent(in) :: parsed
        type(key_spec_t), intent(in) :: schema(:)
        type(error_t), allocatable, intent(out) :: err
        type(alias_t), intent(in), optional :: aliases(:)
        character(len=:), allocatable :: lines, keys
        character(len=16), allocatable :: groups(:)
        integer :: j, n_unknown

        lines = ''
        allocate (groups(0))
        n_unknown = 0
        do j = 1, size(parsed%items)
            associate (item => parsed%items(j))
                if (find_key(schema, item%group, item%key) > 0) cycle
                n_unknown = n_unknown + 1
                if (.not. any(groups == item%group)) &
                    groups = [character(len=16) :: groups, item%group]
                lines = lines//new_line('a')//"  "//at(source, item%line)//"&"//item%group// &
                        ": "//unknown_key(schema, item%group, name_of(item), aliases)
            end associate
        end do
        if (n_unknown == 0) return
        if (n_unknown == 1) then
            call set_error(err, lines(4:)//keys_of(schema, trim(groups(1))))
            return
        end if
        lines = source//": "//fmt_int(n_unknown)//" unknown keys:"//lines
        do j = 1, size(groups)
            keys = keys_of(schema, trim(groups(j)))
            lines = lines//new_line('a')//keys(3:)
        end do
        call set_error(err, lines)
    end subroutine check_keys

    !> The key of `item` as written, without a subscript (its case kept).
    pure function name_of(item) result(name)
        type(item_t), intent(in) :: item
        character(len=:), allocatable :: name

        name = item%written
        if (item%subscripted) name = name(:index(name, '(') - 1)
    end function name_of

    !> `where` starts the message (file:line: &group: ).
    subroutine check_item(where, text, item, schema, err)
        character(len=*), intent(in) :: where, text
        type(item_t), intent(in) :: item
        type(key_spec_t), intent(in) :: schema(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: k, j
        character(len=:), allocatable :: bad_value, too_large

        k = find_key(schema, item%group, item%key)
        if (k == 0) then
            call set_error(err, where//unknown_key(schema, item%group, name_of(item))// &
                           keys_of(schema, item%group))
            return
        end if
        do j = item%n_tokens, 1, -1
            associate (token => text(item%value_first(j):item%value_last(j)))
                if (.not. is_value_of(token, schema(k)%kind)) then
                    bad_value = token
                else if (.not. fits(token, schema(k))) then
                    too_large = token
                end if
            end associate
        end do
        if (item%subscripted .and. .not. schema(k)%list) then
            call set_error(err, where//item%written//": "//item%key//" takes one value, "// &
                           "not a list")
        else if (item%n_values == 0) then
            call set_error(err, where//item%key//" = has no value; "//item%key//" takes "// &
                           trim(type_names(schema(k)%kind)))
        else if (allocated(bad_value)) then
            call set_error(err, where//item%key//" = "//bad_value//" is not "// &
                           trim(type_names(schema(k)%kind))//"; "//item%key//" takes "// &
                           trim(type_names(schema(k)%kind)))
        else if (item%n_values > 1 .and. .not. schema(k)%list) then
            call set_error(err, where//item%key//" has "//fmt_int(item%n_values)// &
                           " values; it takes one, "//trim(type_names(schema(k)%kind)))
        else if (item%n_values > schema(k)%most) then
            call set_error(err, where//item%key//" has "//fmt_int(item%n_values)// &
                           " values; an input takes at most "//fmt_int(schema(k)%most))
        else if (allocated(too_large)) then
            call set_error(err, where//item%key//" = "//too_large//" is beyond "// &
                           range_words(schema(k)))
        end if
    end subroutine check_item

    !> Can the value `token` (of the key's type) be stored? The namelist reader's own words
    !> for one that cannot ("Integer overflow while reading item 2") name no key, and a real
    !> beyond double precision would be read as infinity.
    logical function fits(token, spec)
        character(len=*), intent(in) :: token
        type(key_spec_t), intent(in) :: spec
        character(len=:), allocatable :: v
        integer(int64) :: i
        integer :: ios

        fits = .true.
        v = without_repeat(token)
        if (len(v) == 0) return
        select case (spec%kind)
        case (key_integer)
            read (v, *, iostat=ios) i
            fits = ios == 0
            if (fits .and. .not. spec%wide) fits = i >= -huge(1) - 1_int64 .and. i <= huge(1)
        case (key_real)
            ! (from the text: reading 1e400 would overflow, a floating-point trap when the
            ! build traps overflows)
            fits = decimal_magnitude(v) <= 300
        end select
    end function fits

    !> About log10 |x| + 1 of the real literal v: the place of its first significant digit
    !> (1 for 1.5, 0 for 0.5, -2 for 0.005) plus its exponent; 0 when it has no significant
    !> digit (zero), or no digit at all (NaN, Inf).
    pure integer function decimal_magnitude(v) result(magnitude)
        character(len=*), intent(in) :: v
        integer :: first, point, mark, ios
        integer(int64) :: e

        magnitude = 0
        mark = scan(v, 'eEdD')
        if (mark == 0) mark = len(v) + 1
        first = scan(v(:mark - 1), '123456789')
        if (first == 0) return
        point = index(v(:mark - 1), '.')
        if (point == 0) point = mark
        ! digits from the first significant one to the point, or minus the zeros between the
        ! point and it
        magnitude = point - first
        if (first > point) magnitude = magnitude + 1
        if (mark >= len(v)) return
        read (v(mark + 1:), *, iostat=ios) e
        ! (an exponent beyond 64 bits is surely beyond any limit, one way or the other)
        if (ios /= 0) e = merge(-huge(1), huge(1), v(mark + 1:mark + 1) == '-')
        magnitude = int(max(-int(huge(1), int64), min(int(huge(1), int64), magnitude + e)))
    end function decimal_magnitude

    !> The range of the key's type, for a message.
    pure function range_words(spec) result(words)
        type(key_spec_t), intent(in) :: spec
        character(len=:), allocatable :: words

        if (spec%kind == key_real) then
            words = "double precision (|x| < 1e300)"
        else if (spec%wide) then
            words = "the range of 64-bit integers [-"//fmt_int8(huge(1_int64))//" - 1, "// &
                    fmt_int8(huge(1_int64))//"]"
        else
            words = "the range of 32-bit integers [-2147483648, "//fmt_int(huge(1))//"]"
        end if
    end function range_words

    !> `text` with `spec` (`group.key=value`) applied: every `key = ...` of that group is
    !> removed and `key = value` is put at the end of the group (a new group at the end of the
    !> text if there is none). A string value may be given without quotes. `aliases`: as for
    !> check_namelist.
    subroutine apply_override(text, spec, schema, err, aliases)
        character(len=:), allocatable, intent(inout) :: text
        character(len=*), intent(in) :: spec
        type(key_spec_t), intent(in) :: schema(:)
        type(error_t), allocatable, intent(out) :: err
        type(alias_t), intent(in), optional :: aliases(:)
        character(len=:), allocatable :: group, key, value, assignment
        type(parsed_t) :: parsed
        integer :: dot, eq, k, j, g
        logical :: bad

        dot = index(spec, '.')
        eq = index(spec, '=')
        if (dot < 2 .or. eq < dot + 2) then
            call set_error(err, "--set "//spec//": write it as group.key=value, "// &
                           "e.g. chain.amplitude=2.2")
            return
        end if
        group = lower(spec(:dot - 1))
        key = lower(spec(dot + 1:eq - 1))
        value = trim(adjustl(spec(eq + 1:)))
        if (.not. any(schema%group == group)) then
            call set_error(err, "--set "//spec//": unknown group &"//group// &
                           suggestion(group, group_names(schema), '&')//". The groups are "// &
                           listed(group_names(schema), '&'))
            return
        end if
        k = find_key(schema, group, key)
        if (k == 0) then
            call set_error(err, "--set "//spec//": &"//group//": "// &
                           unknown_key(schema, group, trim(adjustl(spec(dot + 1:eq - 1))), &
                                       aliases)//keys_of(schema, group))
            return
        end if
        if (schema(k)%kind == key_string .and. scan(value, "'""") == 0) &
            value = "'"//value//"'"
        assignment = key//" = "//value
        call parse(text, parsed)
        do j = size(parsed%items), 1, -1
            associate (item => parsed%items(j))
                if (item%group == group .and. item%key == key) &
                    text = text(:item%first - 1)//text(after_separator(text, item%last) + 1:)
            end associate
        end do
        call parse(text, parsed)
        g = 0
        do j = 1, size(parsed%groups)
            if (parsed%groups(j)%name == group .and. parsed%groups(j)%close > 0) g = j
        end do
        if (g == 0) then
            text = text//new_line('a')//"&"//group//" "//assignment//" /"//new_line('a')
        else
            associate (close => parsed%groups(g)%close)
                text = text(:close - 1)//" "//assignment//" "//text(close:)
            end associate
        end if
        call parse("&"//group//" "//assignment//" /", parsed)
        if (size(parsed%groups) /= 1 .or. size(parsed%items) /= 1 .or. &
            parsed%loose_first > 0 .or. parsed%stray_first > 0) then
            bad = .true.
        else
            bad = parsed%groups(1)%close /= len("&"//group//" "//assignment//" /")
        end if
        if (bad) then
            call set_error(err, "--set "//spec//": the value would end the group, start "// &
                           "another or comment out the rest; a value holds no '/', '&' or "// &
                           "'!' outside quotes")
            return
        end if
        call check_item("--set "//spec//": &"//group//": ", "&"//group//" "//assignment// &
                        " /", parsed%items(1), schema, err)
    end subroutine apply_override

    !> The keys of `group`, in schema order.
    pure function schema_keys(schema, group) result(names)
        type(key_spec_t), intent(in) :: schema(:)
        character(len=*), intent(in) :: group
        character(len=16), allocatable :: names(:)
        integer :: i, k

        ! (a loop, not pack(schema%name, ...): the component array would be copied)
        allocate (names(count(schema%group == group)))
        k = 0
        do i = 1, size(schema)
            if (schema(i)%group /= group) cycle
            k = k + 1
            names(k) = schema(i)%name
        end do
    end function schema_keys

    !> Is `token` (without its repeat count) a value of type `kind`?
    pure logical function is_value_of(token, kind)
        character(len=*), intent(in) :: token
        integer, intent(in) :: kind
        character(len=:), allocatable :: v

        v = without_repeat(token)
        if (len(v) == 0) then
            is_value_of = .true.
            return
        end if
        select case (kind)
        case (key_integer)
            is_value_of = is_integer(v)
        case (key_real)
            is_value_of = is_number(v)
        case (key_logical)
            is_value_of = is_logical(v)
        case default
            is_value_of = .true.
        end select
    end function is_value_of

    ! ---- messages ----

    pure function at(source, line) result(text)
        character(len=*), intent(in) :: source
        integer, intent(in) :: line
        character(len=:), allocatable :: text

        text = source//":"//fmt_int(line)//": "
    end function at

    !> "unknown key 'written'" and what it may have meant: the key an alias stands for, or
    !> the nearest key of the group, and the group that has a key of that name.
    function unknown_key(schema, group, written, aliases) result(text)
        type(key_spec_t), intent(in) :: schema(:)
        character(len=*), intent(in) :: group, written
        type(alias_t), intent(in), optional :: aliases(:)
        character(len=:), allocatable :: text, key, hint
        integer :: j

        key = lower(written)
        hint = ''
        if (present(aliases)) hint = alias_hint(aliases, group, written)
        if (len(hint) == 0) hint = suggestion(key, schema_keys(schema, group), "'")
        text = "unknown key '"//written//"'"//hint
        do j = 1, size(schema)
            if (schema(j)%name == key .and. schema(j)%group /= group) then
                text = text//" ('"//key//"' is a key of &"//trim(schema(j)%group)//")"
                exit
            end if
        end do
    end function unknown_key

    !> ". The keys of &group are ..."
    pure function keys_of(schema, group) result(text)
        type(key_spec_t), intent(in) :: schema(:)
        character(len=*), intent(in) :: group
        character(len=:), allocatable :: text

        text = ". The keys of &"//group//" are "//listed(schema_keys(schema, group), '')
    end function keys_of

    !> " (did you mean 'key'? S is <meaning>)" when `written` is an alias (case-blind,
    !> as the reader is; the alias written in the same case first), or nothing. Aliases that
    !> differ only in case are one name to the reader: then every key it may mean is named.
    function alias_hint(aliases, group, written) result(text)
        type(alias_t), intent(in) :: aliases(:)
        character(len=*), intent(in) :: group, written
        character(len=:), allocatable :: text, keys
        integer :: j, best, n_same

        text = ''
        best = 0
        n_same = 0
        do j = 1, size(aliases)
            if (lower(trim(aliases(j)%symbol)) /= lower(written)) cycle
            n_same = n_same + 1
            if (best == 0 .or. trim(aliases(j)%symbol) == written) best = j
        end do
        if (best == 0) return
        associate (a => aliases(best))
            text = " (did you mean '"//trim(a%key)//"'"
            if (a%group /= group) text = text//", a key of &"//trim(a%group)
            text = text//"? "//trim(a%symbol)//" is "//trim(a%meaning)
            if (n_same > 1) then
                text = text//"; keys are case-blind, so "//trim(a%symbol)
                keys = "'"//trim(a%key)//"'"
                do j = 1, size(aliases)
                    if (j == best .or. lower(trim(aliases(j)%symbol)) /= lower(written)) cycle
                    text = text//" and "//trim(aliases(j)%symbol)//" ("// &
                           trim(aliases(j)%meaning)//")"
                    keys = keys//" or '"//trim(aliases(j)%key)//"'"
                end do
                text = text//" are one name here: write "//keys
            end if
        end associate
        text = text//")"
    end function alias_hint

    !> " (did you mean 'x'?)" (or &x) for the candidate nearest to `word` (at most two edits,
    !> and fewer than half its letters), or nothing.
    pure function suggestion(word, candidates, quote) result(text)
        character(len=*), intent(in) :: word, quote
        character(len=*), intent(in) :: candidates(:)
        character(len=:), allocatable :: text
        integer :: j, d, best, best_j

        text = ''
        best = huge(1)
        best_j = 0
        do j = 1, size(candidates)
            d = edit_distance(word, trim(candidates(j)))
            if (d < best) then
                best = d
                best_j = j
            end if
        end do
        if (best_j == 0 .or. best > 2 .or. 2*best >= max(len(word), 2)) return
        text = " (did you mean "//quote//trim(candidates(best_j))
        if (quote == "'") text = text//quote
        text = text//"?)"
    end function suggestion

    !> Edits (insert, delete, substitute, swap of neighbours) between a and b.
    pure integer function edit_distance(a, b) result(d)
        character(len=*), intent(in) :: a, b
        integer :: table(0:len(a), 0:len(b)), i, j, cost

        table(:, 0) = [(i, i=0, len(a))]
        table(0, :) = [(j, j=0, len(b))]
        do i = 1, len(a)
            do j = 1, len(b)
                cost = merge(0, 1, a(i:i) == b(j:j))
                table(i, j) = min(table(i - 1, j) + 1, table(i, j - 1) + 1, &
                                  table(i - 1, j - 1) + cost)
                if (i > 1 .and. j > 1) then
                    if (a(i:i) == b(j - 1:j - 1) .and. a(i - 1:i - 1) == b(j:j)) &
                        table(i, j) = min(table(i, j), table(i - 2, j - 2) + 1)
                end if
            end do
        end do
        d = table(len(a), len(b))
    end function edit_distance

    pure function listed(names, prefix) result(text)
        character(len=*), intent(in) :: names(:), prefix
        character(len=:), allocatable :: text
        integer :: j

        text = ''
        do j = 1, size(names)
            if (j > 1) text = text//', '
            text = text//prefix//trim(names(j))
        end do
    end function listed

    !> The groups of the schema, each once, in order.
    pure function group_names(schema) result(names)
        type(key_spec_t), intent(in) :: schema(:)
        character(len=16), allocatable :: names(:)
        integer :: j

        allocate (names(0))
        do j = 1, size(schema)
            if (.not. any(names == schema(j)%group)) names = [names, schema(j)%group]
        end do
    end function group_names

    integer function find_key(schema, group, key) result(k)
        type(key_spec_t), intent(in) :: schema(:)
        character(len=*), intent(in) :: group, key
        integer :: j

        k = 0
        do j = 1, size(schema)
            if (schema(j)%group == group .and. schema(j)%name == key) k = j
        end do
    end function find_key

end module chain_namelist
