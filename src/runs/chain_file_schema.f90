!> The questions asked of the file schema (chain_file_table): the entry of a path, and its
!> dimensions, long name and reduced unit in one file (the table's placeholders resolved); the
!> reduced unit of a model parameter (one answer each: the /params entry's); and the whole
!> table as the JSON of `impactchain --schema` (its "outputs").
!> Infrastructure, no model section.
module chain_file_schema
    use chain_file_table, only: output_entry_t, output_table
    implicit none
    private
    public :: output_entry_t, output_entry, entry_dims, entry_long_name, entry_model_units
    public :: entry_is_coordinate, parameter_model_units, output_schema_json

    character(len=*), parameter :: parameter_mark = '{parameter}'

contains

    !> The entry of `path` ('strobe/x' or '/strobe/x', '/params/@omega'); where two entries
    !> share a path (/census/point), the one whose `when` is `when`. None: an empty path.
    function output_entry(path, when) result(e)
        character(len=*), intent(in) :: path
        character(len=*), intent(in), optional :: when
        type(output_entry_t) :: e
        type(output_entry_t), allocatable :: t(:)
        character(len=:), allocatable :: key
        integer :: i

        key = path
        if (key(1:1) /= '/') key = '/'//key
        t = output_table()
        do i = 1, size(t)
            if (t(i)%path /= key) cycle
            if (present(when)) then
                if (t(i)%when /= when) cycle
            end if
            e = t(i)
            return
        end do
        e = output_entry_t('', '', '', '', '', '', '', '', '')
    end function output_entry

    !> The entry's dimensions in a file: `name?` kept only with `axes` = 2 (a 2-D sweep), of
    !> `a|b` the `along`-th (default 1).
    pure function entry_dims(e, axes, along) result(dims)
        type(output_entry_t), intent(in) :: e
        integer, intent(in), optional :: axes, along
        character(len=:), allocatable :: dims, word
        integer :: start, last, bar

        dims = ''
        start = 1
        do while (start <= len(e%dims))
            last = index(e%dims(start:), ' ')
            last = merge(len(e%dims), start + last - 2, last == 0)
            word = e%dims(start:last)
            start = last + 2
            if (word(len(word):) == '?') then
                if (.not. present(axes)) cycle
                if (axes /= 2) cycle
                word = word(:len(word) - 1)
            end if
            bar = index(word, '|')
            if (bar > 0) then
                if (take_second(along)) then
                    word = word(bar + 1:)
                else
                    word = word(:bar - 1)
                end if
            end if
            if (len(dims) > 0) dims = dims//' '
            dims = dims//word
        end do
    contains
        pure logical function take_second(along)
            integer, intent(in), optional :: along
            take_second = .false.
            if (present(along)) take_second = along == 2
        end function take_second
    end function entry_dims

    !> A coordinate variable: a dataset whose one dimension is its own name.
    pure logical function entry_is_coordinate(e)
        type(output_entry_t), intent(in) :: e
        integer :: slash

        slash = index(e%path, '/', back=.true.)
        entry_is_coordinate = e%kind == 'dataset' .and. e%dims == e%path(slash + 1:)
    end function entry_is_coordinate

    !> The long name, with the swept or continued `parameter`'s name for its placeholder.
    pure function entry_long_name(e, parameter) result(text)
        type(output_entry_t), intent(in) :: e
        character(len=*), intent(in), optional :: parameter
        character(len=:), allocatable :: text
        integer :: at

        text = e%long_name
        at = index(text, parameter_mark)
        if (at > 0 .and. present(parameter)) &
            text = text(:at - 1)//parameter//text(at + len(parameter_mark):)
    end function entry_long_name

    !> The reduced unit ('' for none), that of `parameter` for the placeholder.
    function entry_model_units(e, parameter) result(units)
        type(output_entry_t), intent(in) :: e
        character(len=*), intent(in), optional :: parameter
        character(len=:), allocatable :: units

        units = e%model_units
        if (units == parameter_mark) then
            units = ''
            if (present(parameter)) units = parameter_model_units(parameter)
        end if
    end function entry_model_units

    !> The reduced unit of model parameter `name` (amplitude, omega, damping, restitution,
    !> spacing, ...): that of its /params entry; '' for a pure number or an unknown name.
    function parameter_model_units(name) result(units)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: units
        type(output_entry_t) :: e

        e = output_entry('/params/@'//name)
        if (len(e%path) == 0) e = output_entry('/params/'//name)
        units = e%model_units
    end function parameter_model_units

    !> The table as a JSON array, one object per line (the "outputs" of `--schema`):
    !> file, path, kind, dims (a list), dtype, units, model_units (null: none), long_name,
    !> when.
    function output_schema_json() result(json)
        character(len=:), allocatable :: json
        type(output_entry_t), allocatable :: t(:)
        character(len=:), allocatable :: model_units
        integer :: i

        t = output_table()
        json = '['
        do i = 1, size(t)
            model_units = 'null'
            if (len(t(i)%model_units) > 0) model_units = quoted(t(i)%model_units)
            json = json//new_line('a')//'{"file": '//quoted(t(i)%file)//', "path": '// &
                   quoted(t(i)%path)//', "kind": '//quoted(t(i)%kind)//', "dims": '// &
                   word_list(t(i)%dims)//', "dtype": '//quoted(t(i)%dtype)//', "units": '// &
                   quoted(t(i)%units)//', "model_units": '//model_units//', "long_name": '// &
                   quoted(t(i)%long_name)//', "when": '//quoted(t(i)%when)//'}'
            if (i < size(t)) json = json//','
        end do
        json = json//new_line('a')//']'
    end function output_schema_json

    !> A JSON string (the table's texts hold no control characters).
    pure function quoted(text) result(json)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: json
        integer :: i

        json = '"'
        do i = 1, len(text)
            if (text(i:i) == '"' .or. text(i:i) == '\') json = json//'\'
            json = json//text(i:i)
        end do
        json = json//'"'
    end function quoted

    !> Blank-separated words as a JSON list of strings.
    pure function word_list(words) result(json)
        character(len=*), intent(in) :: words
        character(len=:), allocatable :: json
        integer :: start, last

        json = '['
        start = 1
        do while (start <= len(words))
            last = index(words(start:), ' ')
            last = merge(len(words), start + last - 2, last == 0)
            if (len(json) > 1) json = json//', '
            json = json//quoted(words(start:last))
            start = last + 2
        end do
        json = json//']'
    end function word_list

end module chain_file_schema
