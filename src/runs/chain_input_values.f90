!> The values of an input, key by key of the input schema (chain_inputs): read from the text
!> that chain_namelist parsed (no `namelist` statement per group), with each key's default
!> when the text leaves it out, checked against the table's ranges and choices, and echoed
!> back as namelist text. Values are kept as namelist text and converted by Fortran's
!> list-directed read, the conversion of the compiler's namelist reader.
module chain_input_values
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int, fmt_int8
    use chain_exact, only: exact, fmt_logical, namelist_string
    use chain_namelist, only: token_t, given_t, given_items, lower
    use chain_inputs, only: input_key_t, input_keys, find_input, check_input, choices_listed, &
                            key_integer, key_real, key_logical, key_string
    implicit none
    private
    public :: input_values_t, read_inputs, check_inputs, echo_inputs, set_input
    public :: is_given, has_value, list_count
    public :: real_input, int_input, int8_input, flag_input, string_input
    public :: reals_input, strings_input

    !> One key: its values as written (or resolved by the reader); none allocated: no value.
    type :: input_value_t
        logical :: given = .false.  !! written in the input, not a default
        type(token_t), allocatable :: values(:)
    end type input_value_t

    !> Every key of the table, in its order.
    type :: input_values_t
        type(input_value_t), allocatable :: keys(:)
    end type input_values_t

contains

    !> The values of `text`, which check_namelist accepted: given, or the table's defaults.
    subroutine read_inputs(text, store, err)
        character(len=*), intent(in) :: text
        type(input_values_t), intent(out) :: store
        type(error_t), allocatable, intent(out) :: err
        type(given_t), allocatable :: given(:)
        integer :: j, k

        allocate (store%keys(size(input_keys)))
        do k = 1, size(input_keys)
            if (len_trim(input_keys(k)%default) > 0) &
                call set_input(store, input_keys(k)%group, input_keys(k)%name, &
                               trim(input_keys(k)%default))
        end do
        call given_items(text, given)
        do j = 1, size(given)
            k = find_input(given(j)%group, given(j)%key)
            if (k == 0) cycle
            call put_given(store%keys(k), input_keys(k)%list, given(j), err)
            if (allocated(err)) return
        end do
    end subroutine read_inputs

    !> `key = v` replaces the default; `key(i) = v, w` sets entries i, i + 1 of a list.
    subroutine put_given(slot, list, given, err)
        type(input_value_t), intent(inout) :: slot
        logical, intent(in) :: list
        type(given_t), intent(in) :: given
        type(error_t), allocatable, intent(out) :: err
        type(token_t), allocatable :: values(:)
        integer :: j, last

        if (given%first < 1) then
            call set_error(err, "&"//given%group//": "//given%key//"'s subscript is not "// &
                           "an index from 1")
            return
        end if
        if (.not. list) then
            if (given%values(1)%text == '') return
            slot%values = given%values
            slot%given = .true.
            return
        end if
        if (.not. slot%given) then
            ! (a list given replaces its default as a whole)
            if (allocated(slot%values)) deallocate (slot%values)
            allocate (slot%values(0))
        end if
        last = given%first + size(given%values) - 1
        allocate (values(max(last, size(slot%values))))
        do j = 1, size(values)
            values(j)%text = ''
            if (j <= size(slot%values)) values(j)%text = slot%values(j)%text
        end do
        do j = 1, size(given%values)
            if (given%values(j)%text /= '') values(given%first + j - 1)%text = given%values(j)%text
        end do
        call move_alloc(values, slot%values)
        slot%given = .true.
    end subroutine put_given

    !> Every given value against its key's static range and choices (chain_inputs).
    subroutine check_inputs(store, err)
        type(input_values_t), intent(in) :: store
        type(error_t), allocatable, intent(out) :: err
        type(input_key_t) :: spec
        integer :: k

        do k = 1, size(input_keys)
            spec = input_keys(k)
            if (.not. store%keys(k)%given .or. spec%list .or. spec%dynamic) cycle
            select case (spec%kind)
            case (key_real)
                call check_input(err, trim(spec%group), trim(spec%name), &
                                 x=real_input(store, trim(spec%group), trim(spec%name)))
            case (key_integer)
                call check_input(err, trim(spec%group), trim(spec%name), &
                                 i=int8_input(store, trim(spec%group), trim(spec%name)))
            case (key_string)
                call check_choice(err, k, string_input(store, trim(spec%group), &
                                                       trim(spec%name)))
            end select
            if (allocated(err)) return
        end do
    end subroutine check_inputs

    !> "&group: key = 'v' is not one of 'a', 'b'" (any case, blanks around ignored).
    subroutine check_choice(err, k, value)
        type(error_t), allocatable, intent(inout) :: err
        integer, intent(in) :: k
        character(len=*), intent(in) :: value

        associate (choices => input_keys(k)%choices)
            if (len_trim(choices) == 0) return
            ! (a leading blank in choices allows '')
            if (index(' '//trim(choices)//' ', ' '//lower(trim(adjustl(value)))//' ') > 0) return
            call set_error(err, "&"//trim(input_keys(k)%group)//": "// &
                           trim(input_keys(k)%name)//" = '"//trim(adjustl(value))// &
                           "' is not one of "//choices_listed(choices))
        end associate
    end subroutine check_choice

    !> The values as namelist text, a line per group of `groups`: every key with a value, in
    !> table order (a key whose echo_default is false only when given), reals to full precision.
    function echo_inputs(store, groups) result(text)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: groups(:)
        character(len=:), allocatable :: text, line
        type(input_key_t) :: spec
        integer :: g, k

        text = ''
        do g = 1, size(groups)
            line = ''
            do k = 1, size(input_keys)
                spec = input_keys(k)
                associate (slot => store%keys(k))
                    if (spec%group /= groups(g) .or. .not. allocated(slot%values)) cycle
                    if (size(slot%values) == 0) cycle
                    if (.not. spec%echo_default .and. .not. slot%given) cycle
                    if (len(line) > 0) line = line//', '
                    line = line//trim(spec%name)//" = "//echo_values(k, slot%values)
                end associate
            end do
            text = text//"&"//trim(groups(g))//" "//line//" /"//new_line('a')
        end do
    end function echo_inputs

    function echo_values(k, values) result(text)
        integer, intent(in) :: k
        type(token_t), intent(in) :: values(:)
        character(len=:), allocatable :: text, piece, buffer
        integer :: j, used

        allocate (character(len=max(64, 24*size(values))) :: buffer)
        used = 0
        do j = 1, size(values)
            piece = echo_value(k, values(j)%text)
            if (j > 1) piece = ', '//piece
            if (used + len(piece) > len(buffer)) buffer = buffer//repeat(' ', len(buffer))
            buffer(used + 1:used + len(piece)) = piece
            used = used + len(piece)
        end do
        text = buffer(:used)
    end function echo_values

    function echo_value(k, token) result(text)
        integer, intent(in) :: k
        character(len=*), intent(in) :: token
        character(len=:), allocatable :: text

        select case (input_keys(k)%kind)
        case (key_real)
            text = exact(to_real(token))
        case (key_integer)
            text = fmt_int8(to_int8(token))
        case (key_logical)
            text = fmt_logical(to_flag(token))
        case default
            text = unquoted(token)
            if (len_trim(input_keys(k)%choices) > 0) text = lower(trim(adjustl(text)))
            text = namelist_string(text)
        end select
    end function echo_value

    !> Put a resolved value (namelist text) for group.key, as if given: the echo shows it.
    subroutine set_input(store, group, key, text)
        type(input_values_t), intent(inout) :: store
        character(len=*), intent(in) :: group, key, text
        integer :: k

        k = find_input(group, key)
        if (k == 0) error stop "chain_input_values: set_input of a key not in the table"
        if (allocated(store%keys(k)%values)) deallocate (store%keys(k)%values)
        allocate (store%keys(k)%values(1))
        store%keys(k)%values(1)%text = text
    end subroutine set_input

    logical function is_given(store, group, key)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key

        is_given = store%keys(slot_of(group, key))%given
    end function is_given

    logical function has_value(store, group, key)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key

        associate (slot => store%keys(slot_of(group, key)))
            has_value = allocated(slot%values)
            if (has_value) has_value = size(slot%values) > 0
        end associate
    end function has_value

    !> How many leading values of a list are given; -1 if they are not consecutive from 1.
    integer function list_count(store, group, key) result(m)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key
        integer :: j

        m = 0
        associate (slot => store%keys(slot_of(group, key)))
            if (.not. allocated(slot%values)) return
            do while (m < size(slot%values))
                if (slot%values(m + 1)%text == '') exit
                m = m + 1
            end do
            if (any([(slot%values(j)%text /= '', j=m + 1, size(slot%values))])) m = -1
        end associate
    end function list_count

    real(wp) function real_input(store, group, key) result(x)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key

        x = to_real(first_text(store, group, key))
    end function real_input

    integer function int_input(store, group, key) result(i)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key

        i = int(to_int8(first_text(store, group, key)))
    end function int_input

    integer(i8) function int8_input(store, group, key) result(i)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key

        i = to_int8(first_text(store, group, key))
    end function int8_input

    logical function flag_input(store, group, key) result(flag)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key

        flag = to_flag(first_text(store, group, key))
    end function flag_input

    !> The string without its quotes ('' when the key has no value).
    function string_input(store, group, key) result(text)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key
        character(len=:), allocatable :: text

        text = unquoted(first_text(store, group, key))
    end function string_input

    !> The leading consecutive values of a list (list_count of them).
    function reals_input(store, group, key) result(x)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key
        real(wp), allocatable :: x(:)
        integer :: j

        allocate (x(max(0, list_count(store, group, key))))
        associate (slot => store%keys(slot_of(group, key)))
            do j = 1, size(x)
                x(j) = to_real(slot%values(j)%text)
            end do
        end associate
    end function reals_input

    !> A list of strings: entry j, or '' where none is given.
    function strings_input(store, group, key, n) result(texts)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key
        integer, intent(in) :: n
        character(len=64) :: texts(n)
        integer :: j

        texts = ''
        associate (slot => store%keys(slot_of(group, key)))
            if (.not. allocated(slot%values)) return
            do j = 1, min(n, size(slot%values))
                texts(j) = unquoted(slot%values(j)%text)
            end do
        end associate
    end function strings_input

    integer function slot_of(group, key) result(k)
        character(len=*), intent(in) :: group, key

        k = find_input(group, key)
        if (k == 0) error stop "chain_input_values: a key not in the table"
    end function slot_of

    function first_text(store, group, key) result(text)
        type(input_values_t), intent(in) :: store
        character(len=*), intent(in) :: group, key
        character(len=:), allocatable :: text

        ! (a configuration not read from text, made in code: the table's defaults)
        if (.not. allocated(store%keys)) then
            text = trim(input_keys(slot_of(group, key))%default)
            return
        end if
        text = ''
        associate (slot => store%keys(slot_of(group, key)))
            if (.not. allocated(slot%values)) return
            if (size(slot%values) > 0) text = slot%values(1)%text
        end associate
    end function first_text

    ! ---- conversions: list-directed reads, as the namelist reader converts ----

    real(wp) function to_real(token) result(x)
        character(len=*), intent(in) :: token
        integer :: ios

        x = 0
        read (token, *, iostat=ios) x
    end function to_real

    integer(i8) function to_int8(token) result(i)
        character(len=*), intent(in) :: token
        integer :: ios

        i = 0
        read (token, *, iostat=ios) i
    end function to_int8

    logical function to_flag(token) result(flag)
        character(len=*), intent(in) :: token
        integer :: ios

        flag = .false.
        read (token, *, iostat=ios) flag
    end function to_flag

    !> A string value without its delimiters ('it''s' -> it's); an undelimited one as written.
    pure function unquoted(token) result(text)
        character(len=*), intent(in) :: token
        character(len=:), allocatable :: text
        character(len=1) :: quote
        integer :: j

        text = token
        if (len(token) < 2) return
        quote = token(1:1)
        if (quote /= "'" .and. quote /= '"') return
        text = ''
        j = 2
        do while (j < len(token))
            text = text//token(j:j)
            if (token(j:j) == quote) j = j + 1
            j = j + 1
        end do
    end function unquoted

end module chain_input_values
