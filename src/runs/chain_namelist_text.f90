!> The text of a namelist input, read as a person wrote it: its groups, and each `key =
!> values` with its place in the text and the line it is on (for chain_namelist's checks and
!> messages, and for chain_input_values, which reads the values). The syntax: `&group`, then
!> `key = values` (values separated by commas or blanks, `r*value` repeats, quoted strings,
!> `key(i)` subscripts), `!` comments, and `/` (or `&end`) closing the group; text outside
!> groups is kept apart (`stray`), as the compiler's reader ignores it. Infrastructure, no
!> model section.
module chain_namelist_text
    use, intrinsic :: iso_fortran_env, only: int64
    implicit none
    private
    public :: token_t, given_t, item_t, group_t, parsed_t
    public :: parse, given_items, groups_in, same_input, lower, repeats, without_repeat
    public :: is_integer, is_number, is_logical, after_separator

    !> One value of a key as written (quotes kept; '' for a null value, `r*`).
    type :: token_t
        character(len=:), allocatable :: text
    end type token_t

    !> What the text gives a key: its group and name (lower case), the subscript of the first
    !> value (1 without one, 0 for a subscript that is not a number) and the values, each
    !> repeat `r*v` written out.
    type :: given_t
        character(len=:), allocatable :: group, key
        integer :: first = 1
        type(token_t), allocatable :: values(:)
    end type given_t

    !> One `key = values` of the text: where it starts and ends (character positions) and the
    !> line it starts on.
    type :: item_t
        character(len=:), allocatable :: group, key, written
        integer :: line = 0, first = 0, last = 0, n_values = 0
        logical :: subscripted = .false.
        logical :: comment_first = .false. !! a comment between `=` and the first value
        integer :: n_tokens = 0 !! value tokens, at value_first(:n_tokens), value_last(:n_tokens)
        integer, allocatable :: value_first(:), value_last(:)
    end type item_t

    !> One group of the text: name, line, and the position of its closing `/` (0: none).
    type :: group_t
        character(len=:), allocatable :: name
        integer :: line = 0, close = 0
    end type group_t

    !> The text's groups and items, and the first text that belongs to neither (outside any
    !> group: `stray`; in a group but not a value of a key: `loose`), which the reader of the
    !> namelist would drop or fail on: positions first:last and line (first = 0: none).
    type :: parsed_t
        type(group_t), allocatable :: groups(:)
        type(item_t), allocatable :: items(:)
        integer :: stray_first = 0, stray_last = 0, stray_line = 0
        integer :: loose_first = 0, loose_last = 0, loose_line = 0
        character(len=:), allocatable :: loose_group
    end type parsed_t

contains

    !> The end of the blanks and at most one comma after text(last:last): removing an item
    !> with them leaves no empty value (which the reader would take as a null value).
    pure integer function after_separator(text, last) result(end)
        character(len=*), intent(in) :: text
        integer, intent(in) :: last
        logical :: comma

        end = last
        comma = .false.
        do while (end < len(text))
            select case (text(end + 1:end + 1))
            case (' ', achar(9))
            case (',')
                if (comma) exit
                comma = .true.
            case default
                exit
            end select
            end = end + 1
        end do
    end function after_separator

    !> Do two texts give the same input, leaving out the key `ignored` ('group.key')? Key by
    !> key: the same groups in the same order, and in each the same keys (case-blind) with
    !> the same values, token for token, in the same order; blanks, commas between values and
    !> comments do not count.
    logical function same_input(a, b, ignored)
        character(len=*), intent(in) :: a, b, ignored

        same_input = signature(a) == signature(b)
    contains
        function signature(text) result(sig)
            character(len=*), intent(in) :: text
            character(len=:), allocatable :: sig
            type(parsed_t) :: parsed
            integer :: g, j, t

            call parse(text, parsed)
            sig = ''
            do g = 1, size(parsed%groups)
                sig = sig//'&'//parsed%groups(g)%name//' '
            end do
            do j = 1, size(parsed%items)
                associate (item => parsed%items(j))
                    if (item%group//'.'//item%key == ignored) cycle
                    sig = sig//new_line('a')//item%group//'.'//lower(item%written)//'='
                    do t = 1, item%n_tokens
                        sig = sig//text(item%value_first(t):item%value_last(t))//achar(0)
                    end do
                end associate
            end do
        end function signature
    end function same_input

    !> Every `key = values` of a text that check_namelist accepted, in order.
    subroutine given_items(text, given)
        character(len=*), intent(in) :: text
        type(given_t), allocatable, intent(out) :: given(:)
        type(parsed_t) :: parsed
        integer :: j, t, r, used, ios, paren

        call parse(text, parsed)
        allocate (given(size(parsed%items)))
        do j = 1, size(given)
            associate (item => parsed%items(j), g => given(j))
                g%group = item%group
                g%key = item%key
                if (item%subscripted) then
                    paren = index(item%written, '(')
                    read (item%written(paren + 1:scan(item%written, ':)') - 1), *, &
                          iostat=ios) g%first
                    if (ios /= 0) g%first = 0
                end if
                allocate (g%values(item%n_values))
                used = 0
                do t = 1, item%n_tokens
                    associate (token => text(item%value_first(t):item%value_last(t)))
                        do r = 1, min(repeats(token), size(g%values) - used)
                            used = used + 1
                            g%values(used)%text = without_repeat(token)
                        end do
                    end associate
                end do
            end associate
        end do
    end subroutine given_items

    !> The names of the groups in `text`, in order (lower case).
    function groups_in(text) result(names)
        character(len=*), intent(in) :: text
        character(len=16), allocatable :: names(:)
        type(parsed_t) :: parsed
        integer :: j

        call parse(text, parsed)
        allocate (names(size(parsed%groups)))
        do j = 1, size(names)
            names(j) = parsed%groups(j)%name
        end do
    end function groups_in

    !> Groups and items of `text`, with positions and lines.
    pure subroutine parse(text, parsed)
        character(len=*), intent(in) :: text
        type(parsed_t), intent(out) :: parsed
        integer :: pos, line

        allocate (parsed%groups(0), parsed%items(0))
        pos = 1
        line = 1
        do while (pos <= len(text))
            if (text(pos:pos) == '&') then
                call parse_group(text, pos, line, parsed)
            else if (text(pos:pos) == '!') then
                do while (pos < len(text))
                    if (text(pos + 1:pos + 1) == new_line('a')) exit
                    pos = pos + 1
                end do
                pos = pos + 1
            else
                if (text(pos:pos) == new_line('a')) line = line + 1
                if (.not. is_separator(text(pos:pos)) .and. parsed%stray_first == 0) then
                    parsed%stray_first = pos
                    parsed%stray_last = pos
                    parsed%stray_line = line
                    do while (parsed%stray_last < len(text))
                        if (is_separator(text(parsed%stray_last + 1:parsed%stray_last + 1))) &
                            exit
                        parsed%stray_last = parsed%stray_last + 1
                    end do
                end if
                pos = pos + 1
            end if
        end do
    end subroutine parse

    !> The group starting at text(pos:pos) == '&'; pos and line move past its close.
    pure subroutine parse_group(text, pos, line, parsed)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos, line
        type(parsed_t), intent(inout) :: parsed
        type(group_t) :: group
        type(item_t) :: item
        integer :: first, last, token_line, next_first, next_last, next_line, eq
        logical :: in_item, key_follows

        first = pos + 1
        last = pos
        do while (last < len(text))
            if (.not. is_name_char(text(last + 1:last + 1))) exit
            last = last + 1
        end do
        group%name = lower(text(first:last))
        group%line = line
        pos = last + 1
        if (group%name == 'end' .or. len(group%name) == 0) return
        in_item = .false.
        call next_token(text, pos, line, first, last, token_line)
        do while (first > 0)
            if (text(first:last) == '/' .or. lower(text(first:last)) == '&end') then
                group%close = first
                pos = last + 1
                exit
            else if (text(first:first) == '&') then
                pos = first  ! the next group begins: this one is not closed
                exit
            end if
            call next_token(text, pos, line, next_first, next_last, next_line)
            key_follows = .false.
            if (next_first > 0) key_follows = text(next_first:next_last) == '=' .and. &
                                              text(first:last) /= '='
            if (key_follows) then
                if (in_item) parsed%items = [parsed%items, item]
                call start_item(group%name, text(first:last), token_line, first, item)
                in_item = .true.
                eq = next_last
                call next_token(text, pos, line, next_first, next_last, next_line)
                if (next_first > 0) item%comment_first = index(text(eq + 1:next_first - 1), &
                                                               '!') > 0
            else if (in_item .and. text(first:last) /= '=') then
                call add_value(text(first:last), first, last, item)
            else if (parsed%loose_first == 0) then
                parsed%loose_first = first
                parsed%loose_last = last
                parsed%loose_line = token_line
                parsed%loose_group = group%name
            end if
            first = next_first
            last = next_last
            token_line = next_line
        end do
        if (in_item) parsed%items = [parsed%items, item]
        parsed%groups = [parsed%groups, group]
    end subroutine parse_group

    pure subroutine start_item(group, written, line, first, item)
        character(len=*), intent(in) :: group, written
        integer, intent(in) :: line, first
        type(item_t), intent(out) :: item
        integer :: paren

        item%group = group
        item%written = written
        paren = index(written, '(')
        item%subscripted = paren > 0
        if (paren > 0) then
            item%key = lower(written(:paren - 1))
        else
            item%key = lower(written)
        end if
        item%line = line
        item%first = first
        item%last = first + len(written) - 1
        allocate (item%value_first(8), item%value_last(8))
    end subroutine start_item

    pure subroutine add_value(token, first, last, item)
        character(len=*), intent(in) :: token
        integer, intent(in) :: first, last
        type(item_t), intent(inout) :: item

        ! (saturating: counts near huge(1) must not wrap round to a small number)
        item%n_values = int(min(int(huge(1), int64), int(item%n_values, int64) + &
                                repeats(token)))
        item%last = last
        ! capacity doubles: a list of 10^5 values is read in linear time
        if (item%n_tokens == size(item%value_first)) then
            item%value_first = [item%value_first, item%value_first]
            item%value_last = [item%value_last, item%value_last]
        end if
        item%n_tokens = item%n_tokens + 1
        item%value_first(item%n_tokens) = first
        item%value_last(item%n_tokens) = last
    end subroutine add_value

    !> The next token from text(pos:): a quoted string, '=', '/', '&...', or a word (anything
    !> else up to a blank, comma, '=', '/' or '!'); blanks, commas and comments are skipped.
    !> first = 0 at the end of the text.
    pure subroutine next_token(text, pos, line, first, last, token_line)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos, line
        integer, intent(out) :: first, last, token_line
        character(len=1) :: c

        first = 0
        last = 0
        do while (pos <= len(text))
            c = text(pos:pos)
            if (c == new_line('a')) line = line + 1
            if (c == '!') then
                do while (pos < len(text))
                    if (text(pos + 1:pos + 1) == new_line('a')) exit
                    pos = pos + 1
                end do
            else if (.not. is_separator(c)) then
                exit
            end if
            pos = pos + 1
        end do
        if (pos > len(text)) return
        first = pos
        token_line = line
        c = text(pos:pos)
        if (c == "'" .or. c == '"') then
            last = string_end(text, pos)
        else if (c == '=' .or. c == '/') then
            last = pos
        else
            last = pos
            do while (last < len(text))
                if (is_separator(text(last + 1:last + 1)) .or. &
                    scan(text(last + 1:last + 1), "=/!'""") > 0) exit
                last = last + 1
            end do
        end if
        pos = last + 1
    end subroutine next_token

    !> Position of the quote closing the string opened at text(start:start) (a doubled quote
    !> is part of the string); the end of the line if it is not closed.
    pure integer function string_end(text, start) result(last)
        character(len=*), intent(in) :: text
        integer, intent(in) :: start
        character(len=1) :: quote

        quote = text(start:start)
        last = start + 1
        do while (last <= len(text))
            if (text(last:last) == new_line('a')) exit
            if (text(last:last) == quote) then
                if (last == len(text)) return
                if (text(last + 1:last + 1) /= quote) return
                last = last + 1
            end if
            last = last + 1
        end do
        last = last - 1
    end function string_end

    !> How many values a token stands for: `r*value` (or `r*`) is r, else 1.
    pure integer function repeats(token)
        character(len=*), intent(in) :: token
        integer :: star, ios

        repeats = 1
        star = index(token, '*')
        if (star < 2 .or. scan(token(1:1), "'""") > 0) return
        if (verify(token(:star - 1), '0123456789') /= 0) return
        ! (a count too long to read is more values than any key takes)
        read (token(:star - 1), *, iostat=ios) repeats
        if (ios /= 0 .or. star > 10) repeats = huge(1)
    end function repeats

    !> `token` without its repeat count (`3*0.5` -> `0.5`).
    pure function without_repeat(token) result(v)
        character(len=*), intent(in) :: token
        character(len=:), allocatable :: v
        integer :: star

        v = token
        star = index(v, '*')
        if (star > 1 .and. scan(v(1:1), "'""") == 0) then
            if (verify(v(:star - 1), '0123456789') == 0) v = v(star + 1:)
        end if
    end function without_repeat

    pure logical function is_integer(v)
        character(len=*), intent(in) :: v
        integer :: start

        is_integer = .false.
        if (len(v) == 0) return
        start = 1
        if (scan(v(1:1), '+-') > 0) start = 2
        if (len(v) < start) return
        is_integer = verify(v(start:), '0123456789') == 0
    end function is_integer

    !> A real literal: digits with at most one point, an optional exponent (e, E, d, D), or
    !> NaN / Inf / Infinity, each with an optional sign.
    pure logical function is_number(v)
        character(len=*), intent(in) :: v
        character(len=:), allocatable :: w
        integer :: e, start

        start = 1
        if (scan(v(1:1), '+-') > 0) start = 2
        is_number = .false.
        if (len(v) < start) return
        w = lower(v(start:))
        if (w == 'nan' .or. w == 'inf' .or. w == 'infinity') then
            is_number = .true.
            return
        end if
        e = scan(w, 'ed')
        if (e > 0) then
            if (.not. is_integer(w(e + 1:))) return
            w = w(:e - 1)
        end if
        is_number = len(w) > 0 .and. verify(w, '0123456789.') == 0 .and. &
                    count_char(w, '.') <= 1 .and. verify(w, '.') /= 0
    end function is_number

    pure logical function is_logical(v)
        character(len=*), intent(in) :: v
        character(len=:), allocatable :: w

        w = lower(v)
        if (w(1:1) == '.') w = w(2:)
        is_logical = .false.
        if (len(w) == 0) return
        is_logical = w(1:1) == 't' .or. w(1:1) == 'f'
        if (len(w) > 1) is_logical = is_logical .and. &
            (w == 'true' .or. w == 'false' .or. w == 'true.' .or. w == 'false.' .or. &
             w == 't.' .or. w == 'f.')
    end function is_logical

    pure logical function is_separator(c)
        character(len=1), intent(in) :: c
        is_separator = c == ' ' .or. c == ',' .or. c == achar(9) .or. c == achar(13) .or. &
                       c == new_line('a')
    end function is_separator

    pure logical function is_name_char(c)
        character(len=1), intent(in) :: c
        is_name_char = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z') .or. &
                       (c >= '0' .and. c <= '9') .or. c == '_'
    end function is_name_char

    pure integer function count_char(s, c)
        character(len=*), intent(in) :: s
        character(len=1), intent(in) :: c
        integer :: j

        count_char = 0
        do j = 1, len(s)
            if (s(j:j) == c) count_char = count_char + 1
        end do
    end function count_char

    pure function lower(s) result(t)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: j

        t = s
        do j = 1, len(s)
            if (s(j:j) >= 'A' .and. s(j:j) <= 'Z') t(j:j) = achar(iachar(s(j:j)) + 32)
        end do
    end function lower
end module chain_namelist_text
